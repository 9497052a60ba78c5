"""Seed 002's Neural GI network (ngi.neural_gi): data, training and its baselines, sequences, evaluation, report
(README.md in this folder)."""
