"""results/README.md, "What ordering buys as the kernel gets faster" (issue 46): each trace class's own
NoSort speed beside each encoder's speedup and net speedup, in the GPU model (results/gpu-model/
classes-16c0de1) and measured on PoCL (paper-1spp-stream-23a1a19), with scripts/class_speedups.py."""
from class_speedups import profile_dram_gbps, table_lines

from .sets import KERNEL_CLASSES_MODEL, STREAM_CLASSES


def model_block():
    return "\n".join(table_lines([KERNEL_CLASSES_MODEL], "model", profile_dram_gbps())[0])


def pocl_block():
    return "\n".join(table_lines([STREAM_CLASSES], "pocl", profile_dram_gbps())[0])
