"""Knowledge layer: the KnowledgeGraph protocol, the SQLite ConceptNet store and its importers, the
ConceptNet REST client, the Wikipedia fallback, and concept normalisation."""
