"""The trainers of the shipped models (tools/README.md); nets.py holds what they share."""
