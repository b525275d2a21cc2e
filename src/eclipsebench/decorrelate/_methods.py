"""Imports every finished method module so that each registers itself."""
