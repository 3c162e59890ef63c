"""Plain typed data shared by every layer: errors, usage accounting, settings."""
