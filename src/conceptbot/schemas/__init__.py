"""JSON Schemas of the contracts other tools rely on (``plan.schema.json``: ``conceptbot plan --json``)."""
