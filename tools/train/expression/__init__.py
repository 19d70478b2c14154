"""The expression stage's net (docs/cnn.md)."""
