#!/usr/bin/python3
"""torchrun, runnable where Debian's python3-torch 1.13 meets Python 3.11 (Debian 12).

    /usr/bin/python3 -m ngi_train.torchrun --nproc_per_node 2 --module ngi_train.generator.train --config ... --run ...

Takes exactly torchrun's arguments (`--help`). torch 1.13's launcher parses its --redirects / --tee values by
iterating over the IntFlag `Std`, which on Python 3.11 no longer yields the zero member NONE (nor the
combination ALL), so the stock `torchrun` fails before starting any worker with
"AttributeError: 'NoneType' object has no attribute 'get'" (in `to_map`; PyTorch 2.x parses them differently).
This script replaces that parser with one that builds Std(value) directly, then runs torch.distributed.run's
main(). Where `Std.from_str("0")` already works, nothing is patched and this is plain torchrun.
"""

import re
import sys

from torch.distributed.elastic.multiprocessing.api import Std
from torch.distributed.run import main


def _std_from_str(cls, vm):
    """"0".."3" -> Std; "0:3,1:0" -> {local rank: Std} (what torch 1.13's Std.from_str documents)."""
    if re.fullmatch(r"[0-3]", vm):
        return cls(int(vm))
    if re.fullmatch(r"([0-9]+:[0-3])(,[0-9]+:[0-3])*", vm):
        return {int(i): cls(int(v)) for i, v in (m.split(":") for m in vm.split(","))}
    raise ValueError(f"{vm} does not match a number in [0, 3] or a mapping like 0:1,1:3")


if Std.from_str("0") is None:
    Std.from_str = classmethod(_std_from_str)

if __name__ == "__main__":
    sys.exit(main())
