"""The pix2pix generators (surround-aware and single view) and their discriminator: data, training, export,
evaluation, the speed/accuracy ladder and the GI ladder (training/README.md)."""
