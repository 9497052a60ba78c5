"""ngi_train: the training, export and evaluation of every network ngi runs, one package.

Run from the repository root with this folder's parent and the build's Python package on the path (nothing edits
sys.path):

    export PYTHONPATH=$PWD/training:$PWD/build/python
    /usr/bin/python3 -m ngi_train.generator.train --config training/configs/surround.json --dataset DATA --run RUN

Shared by every family: `paths` (the repository, the ngi binary, running it, progress bars), `checkpoint` (atomic
checkpoints and the resumable, SIGINT-safe step loop), `distributed` (torchrun ranks), `torchrun` (the launcher).
Families: `generator` (pix2pix U-Net: data, networks, GAN, train, export, evaluate, the ladders and reports), `ao`
(seed 001's ambient-occlusion MLP), `neural_gi` (seed 002's Neural GI), `voxel_sh` (seed 004's voxel SH networks).
The PyTorch networks ngi is tested against live in the package `ngi` (`ngi.reference_models`, `ngi.neural_gi`,
`ngi.voxel_sh`), shared with the converter and the parity tests; training/README.md has the whole layout.
"""
