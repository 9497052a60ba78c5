"""Running the training and the evaluation on several processes with PyTorch's own engine (torch.distributed).

    torchrun --nproc_per_node 2 --module ngi_train.generator.train ...   (or python3 -m ngi_train.torchrun ...)

torchrun starts one process per rank and sets RANK, WORLD_SIZE, LOCAL_RANK (and MASTER_ADDR / MASTER_PORT) in
their environments; init() reads them. Without them (a plain `python3 -m ngi_train.generator.train`), or with
WORLD_SIZE 1, nothing is initialized and every helper here is the identity of a single process, so the
single-process code path is exactly what it was before distribution existed.

The process group uses NCCL when CUDA is available, gloo otherwise (CPU). Conventions shared by train.py and
evaluate.py:
- rank 0 is the only process that writes into a run or output folder's shared files (run.json, log.jsonl,
  checkpoints, summary JSON) and prints progress; the other ranks only read;
- work is split round-robin: item k of a list belongs to rank k mod world_size (shard());
- results gathered from the ranks are put back into the order a single process would have produced, so a
  merged result is the same, bit for bit, whatever the world size.
"""

import datetime
import os

import numpy as np
import torch
import torch.distributed as dist


class Dist:
    """This process's place in the job: rank, world size, local rank, backend, compute device."""

    def __init__(self, rank=0, world=1, local_rank=0, backend=None, device="cpu"):
        self.rank, self.world, self.local_rank = rank, world, local_rank
        self.backend = backend
        self.device = torch.device(device)

    @property
    def enabled(self):
        return self.world > 1

    @property
    def main(self):
        return self.rank == 0

    def barrier(self):
        if self.enabled:
            dist.barrier()

    def all_reduce_sum(self, values):
        """Sum of a float64 vector over the ranks (the vector itself without distribution). Two ranks' sums are
        exact up to one rounding and the same on every rank (a + b == b + a)."""
        t = torch.as_tensor(values, dtype=torch.float64)
        if not self.enabled:
            return t
        t = t.to(self.device)
        dist.all_reduce(t, op=dist.ReduceOp.SUM)
        return t.cpu()

    def all_reduce_(self, tensor):
        """In-place sum over the ranks of a tensor on self.device."""
        if self.enabled:
            dist.all_reduce(tensor, op=dist.ReduceOp.SUM)
        return tensor

    def all_gather(self, obj):
        """[obj of rank 0, obj of rank 1, ...] on every rank (pickled objects)."""
        if not self.enabled:
            return [obj]
        out = [None] * self.world
        dist.all_gather_object(out, obj)
        return out

    def shard(self, items):
        """The items of this rank: positions rank, rank + world, ... (round robin)."""
        return list(items)[self.rank::self.world]

    def unshard(self, per_rank, count):
        """Inverse of shard: the lists of every rank (all_gather of shard results) back in the original order."""
        out = [None] * count
        for r, part in enumerate(per_rank):
            for k, item in enumerate(part):
                out[r + k * self.world] = item
        return out

    def close(self):
        if self.enabled and dist.is_initialized():
            dist.destroy_process_group()


def init(timeout_minutes=30):
    """Joins the process group torchrun describes in the environment (RANK, WORLD_SIZE, LOCAL_RANK; see the module
    doc). Returns a Dist; a single process (no torchrun, or WORLD_SIZE 1) gets Dist() and no process group."""
    world = int(os.environ.get("WORLD_SIZE", "1"))
    if world <= 1:
        return Dist()
    rank = int(os.environ["RANK"])
    local_rank = int(os.environ.get("LOCAL_RANK", "0"))
    if torch.cuda.is_available():
        backend = "nccl"
        torch.cuda.set_device(local_rank)
        device = f"cuda:{local_rank}"
        # torch.use_deterministic_algorithms(True) on CUDA needs a fixed cuBLAS workspace.
        os.environ.setdefault("CUBLAS_WORKSPACE_CONFIG", ":4096:8")
    else:
        backend, device = "gloo", "cpu"
    dist.init_process_group(backend, rank=rank, world_size=world, timeout=datetime.timedelta(minutes=timeout_minutes))
    return Dist(rank, world, local_rank, backend, device)


def rank_seed(seed, rank, step):
    """The torch seed of rank `rank` > 0 (rank 0 keeps the run's own RNG stream): different per rank, a function of
    (run seed, rank, step at which the rank started) so a resume that cannot restore a rank's RNG state still gets a
    reproducible, fresh stream."""
    return int(np.random.default_rng([seed, 1_000_003, rank, step]).integers(2 ** 62))

