"""Seed 004's voxel SH networks (ngi.voxel_sh): data, training, export, evaluation, report (README.md in this
folder)."""
