"""Preset libraries: listing folders of ``lamp-scene`` JSON safely, saving, thumbnails."""
