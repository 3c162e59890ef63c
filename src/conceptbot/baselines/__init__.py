"""Baselines the product is compared with (SayCan)."""
