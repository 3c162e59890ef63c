"""Model layer: LLM and embedder protocols, backends, model store, caches and the call log."""
