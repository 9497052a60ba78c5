"""Seed 001's ambient-occlusion MLP: ring sampling, training, held-out evaluation (docs/RESULTS_AO.md)."""
