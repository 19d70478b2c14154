"""Measurements the docs cite (docs/decisions.md): kept so that they can be repeated."""
