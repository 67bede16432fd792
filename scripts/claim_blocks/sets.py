"""The committed result sets the quoted figures come from, named once, and the paper's scene columns
with the stand-in that plays each (docs/paper.md, "Scenes")."""
import os

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
EPYC = os.path.join(ROOT, "results", "pocl-cpu-pthread-skylake-avx512-amd-epyc")
XEON = os.path.join(ROOT, "results", "pocl-cpu-pthread-skylake-avx512-intel-xeon")

ONE_SPP = os.path.join(EPYC, "paper-1spp-9dab0ed")
EIGHT_SPP = os.path.join(EPYC, "paper-8spp-9dab0ed", "merged")
CLASSES = os.path.join(XEON, "paper-1spp-classes-da8579b")
# The packet class's 80 cells of Tables 2 and 3 again after the robust packet kernels set up their
# lanes' rays in vector form (issue 40): CLASSES' packet16 cells ran kernels that prepared each lane's
# ray out of line, at 0.37-0.41 of the fast packets' speed on primary rays (docs/trace.md).
PACKET_SETUP = os.path.join(XEON, "paper-1spp-packet-06b6e7c")
# The same 80 cells on the EPYC with the kernels of 139c5a4 (the gathered ray prefetched): packet16, the
# packet widths 8 and 4, the landscape stand-in at the paper's size, and shadow0 per width on landscape and
# sibenik (PACKET_EPYC); both access modes of packet16 and single rays (PACKET_EPYC_ACCESS).
PACKET_EPYC = os.path.join(EPYC, "paper-1spp-packet-139c5a4")
PACKET_EPYC_ACCESS = os.path.join(EPYC, "paper-1spp-access-139c5a4")
# The packet16 cells of PACKET_EPYC's five-scenes and landscape-21m again with the kernels of a4d24f4: packets
# of rays in a row load their rays and store their hits a row at a time (results/history/trace-kernels.md).
PACKET_ROWS = os.path.join(EPYC, "paper-1spp-packet-a4d24f4")
# The packet16 cells of five-scenes again with the kernels of 4399aef (the lowest set bit one tzcnt).
PACKET_TZCNT = os.path.join(EPYC, "paper-1spp-packet-4399aef")
VIEWPORT = os.path.join(EPYC, "paper-viewport-1spp-d8b4b22")
HCC_DIR = os.path.join(EPYC, "paper-hcc-dir-1spp-d8b4b22")
BOUNCES = os.path.join(EPYC, "paper-bounces-1spp-d8b4b22")
SWEEPS = os.path.join(EPYC, "sweeps-d8b4b22")
# The λ sweep on the paper's two other stand-ins (issue 43, item 6), on the Xeon: its SIMT ratios are
# deterministic, so they stand beside the EPYC sets' in one table.
SWEEPS_MORE = os.path.join(XEON, "sweeps-115dd84")
# The Table 4, Table 8 and bounces matrices re-run with --gpu-model rtx3060 (issue 43, item 4): the
# committed sets above have no GPU-model columns.
GPU_MODEL_SETS = os.path.join(ROOT, "results", "gpu-model")
GPU_VIEWPORT = os.path.join(GPU_MODEL_SETS, "paper-viewport-1spp-gm-5382d1e")
GPU_HCC_DIR = os.path.join(GPU_MODEL_SETS, "paper-hcc-dir-1spp-gm-5382d1e")
GPU_BOUNCES = os.path.join(GPU_MODEL_SETS, "paper-bounces-1spp-gm-5382d1e")
AUDIT_ORDER = os.path.join(XEON, "audit-issue43-5382d1e", "sibenik-order")
AUDIT_TWOPOINT_BITS = os.path.join(XEON, "audit-issue43-5382d1e", "twopoint-bits")
AUDIT_TWOPOINT_VARIANTS = os.path.join(XEON, "audit-issue43-5382d1e", "twopoint-variants")
PAPER_SPEEDUPS = os.path.join(ROOT, "results", "gpu-model", "paper_tables.csv")
STREAM_CLASSES = os.path.join(XEON, "paper-1spp-stream-23a1a19")
KERNEL_CLASSES_MODEL = os.path.join(ROOT, "results", "gpu-model", "classes-16c0de1")
CWBVH_DRAM = os.path.join(ROOT, "results", "gpu-model", "cwbvh-dram-9ca3605")
# The same matrix for the other GPU classes (wide8; binary and binary-ww), one set each.
CLASSES_WIDE8 = os.path.join(ROOT, "results", "gpu-model", "classes-wide8-dac824d")
CLASSES_BINARY = os.path.join(ROOT, "results", "gpu-model", "classes-binary-dac824d")

# stand-in scene -> the paper's column it is scored against (results/gpu-model/paper_tables.csv pairs
# them so). `landscape` is scored against the paper's *landscape* column (21.84 M triangles), not Vokselia.
PAPER_COLUMN = {"breakfast_room": "Breakfast", "grey_white_room": "Living room", "sibenik": "Sibenik",
                "multi-instance-real": "MultiInstance", "landscape": "landscape"}
# the order of the paper's columns (Tables 2 and 3), for the stand-ins that have one
PAPER_ORDER = ["breakfast_room", "grey_white_room", "sibenik", "multi-instance-real", "landscape"]

# The first NVIDIA run (a lent H200, results/gpu-nvidia-h200/README.md): every trace class on the
# paper's sibenik and breakfast_room batches, the GPU classes' matrices, the validation matrix.
H200 = os.path.join(ROOT, "results", "gpu-nvidia-h200")
H200_TRACE_LOG = os.path.join(H200, "trace-classes-3182779.log")
H200_CLASSES = [os.path.join(H200, "classes-sb-12e32f2"), os.path.join(H200, "classes-3more-12e32f2")]
H200_VALIDATION = os.path.join(H200, "gpu-validation-12e32f2")
H200_PAPER = os.path.join(H200, "paper-1spp-sb-12e32f2")
# The same matrix run here with --gpu-model h200 (reps 1): the model's predictions for that GPU.
H200_MODEL = os.path.join(ROOT, "results", "gpu-model", "h200-model-12e32f2")
H200_SORTBENCH = os.path.join(H200, "sortbench-12e32f2.md")

# results/README.md from "Format 3" to the end (claim_blocks/reference_sets.py): the three format-2
# reference sets, all from cfebb2c; paper-cfebb2c's SIMT columns walk the binary BVH.
PAPER_CFEBB2C = os.path.join(EPYC, "paper-cfebb2c")
PAPER_SIBENIK = os.path.join(EPYC, "paper-sibenik-cfebb2c")
ACCURACY_COST = os.path.join(EPYC, "accuracy-cost-960x540-cfebb2c")
# the same paper preset's 1-spp cells on the wide BVH (format 3): binary -> wide
FORMAT3_WIDE = ONE_SPP
BASELINES = os.path.join(EPYC, "baselines-bounce1-6c6ecfe")
# results/gpu-model/README.md from "The same on the binary BVH" on (claim_blocks/gpu_model_rest.py): the
# validation's committed per-cell predictions (cells.csv) and reports (validation.md), one folder each.
GPU_VALIDATION_WIDE = GPU_MODEL_SETS
GPU_VALIDATION_BINARY = os.path.join(GPU_MODEL_SETS, "binary")
GPU_VALIDATION_8SPP = os.path.join(GPU_MODEL_SETS, "8spp")
GPU_SCHEDULE_REFILL = os.path.join(GPU_MODEL_SETS, "schedules", "warp-refill")
GPU_SCHEDULE_DYNAMIC = os.path.join(GPU_MODEL_SETS, "schedules", "dynamic-fetch-20")
# results/README.md up to "Beyond the paper" and docs/paper.md, their prose and cost figures
# (claim_blocks/prose_early.py).
SHARED_ROUNDS = os.path.join(XEON, "shared-rounds-ab")
# Issue 42's wall-clock bar side by side with the issue's commit (claim_blocks/protocol_time.py).
PROTOCOL_TIME = os.path.join(EPYC, "protocol-time-ca43944")
PROTOCOL_TIME_PREFETCH = os.path.join(EPYC, "protocol-time-00cb31e")
OCLGRIND = os.path.join(ROOT, "results", "gpu-oclgrind-simulator", "quick-tiny-binary-5230438")
EIGHT_SPP_SHARDS = os.path.join(EPYC, "paper-8spp-9dab0ed", "shards")
# The earlier 8-spp sets (sibenik and breakfast_room; grey_white_room), kept for their history.
EIGHT_SPP_EARLIER = [os.path.join(EPYC, "paper-8spp-4e8c9eb"), os.path.join(EPYC, "paper-8spp-grey_white_room-d8b4b22")]
AUDIT_ENCODEBENCH = os.path.join(XEON, "audit-issue43-5382d1e", "encodebench-sibenik-bounce1.txt")
# Issue 21's encoders (results/README.md, "Beyond the paper"): the matrices, sweeps, studies and the
# paired encode cost, one path each.
NEW_ENCODERS = os.path.join(EPYC, "new-encoders-1spp-d8b4b22")
MLHCC_COST = os.path.join(EPYC, "mlhcc-cost-1spp-f82d974")          # C = 4, the default
MLHCC_COST_C8 = os.path.join(EPYC, "mlhcc-cost-1spp-fbcf847")       # C = 8, the default then
COST_BITS_SWEEP = os.path.join(EPYC, "sweeps-fbcf847")
REGION_V2 = os.path.join(EPYC, "region-v2-1spp-7547e16")
REGION_SWEEPS = os.path.join(EPYC, "sweeps-7547e16")
REGION_CELLS = os.path.join(EPYC, "region-cells-1spp-0a53899")      # the third kernel, run 1
ENCODE_COST = os.path.join(EPYC, "encode-cost-1spp-fa55adf")        # the third kernel, run 2
ENCODE_VERSUS = os.path.join(EPYC, "encode-versus-hcc-b53a04f")
ORDER_STUDY = os.path.join(ROOT, "results", "order-study", "bounce1-960x540.txt")
REGION_STUDY = os.path.join(ROOT, "results", "region-study", "bounce1-1920x1080.txt")
# results/gpu-model/README.md, "What holds, and what does not" (claim_blocks/gpu_model_holds.py): the model
# against the shuffled baseline order, the run and its validation (gpu_model_validate.py --baseline shuffled).
GPU_SHUFFLED_SET = os.path.join(EPYC, "gpu-model-shuffled-1spp-66f45e6")
GPU_MODEL_SHUFFLED = os.path.join(GPU_MODEL_SETS, "shuffled")
