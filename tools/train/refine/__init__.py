"""The landmark refiner and its brow and eye net (docs/cnn.md)."""
