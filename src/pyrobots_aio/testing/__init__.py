"""Test support for robot behaviours: a pytest plugin, fixtures and assertions."""
