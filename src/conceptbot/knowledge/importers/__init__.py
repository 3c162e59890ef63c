"""Streaming importers: each yields :class:`~conceptbot.knowledge.base.Edge` objects from a source
file without loading it into memory, and reports progress in bytes read."""
