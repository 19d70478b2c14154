"""The gaze stage's iris net (docs/gaze.md)."""
