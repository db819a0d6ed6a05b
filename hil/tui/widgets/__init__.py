"""Widgets of the terminal app: braille plots, the navigation bar, the suspension banner."""
