"""Matplotlib figures (imported only by the commands that draw them)."""
