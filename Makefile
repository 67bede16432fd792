# raysort — the two commands that work on a fresh Debian 12 machine:
#   make bench   the main job on the embedded procedural scenes (PoCL, a few minutes)
#   make test    the test suite (ctest)
# Both install the Debian dependencies first when any is missing (scripts/install-deps.sh).

BUILD ?= build
JOBS ?= $(shell nproc 2>/dev/null || echo 2)
CMAKE_FLAGS ?= -DCMAKE_BUILD_TYPE=Release
# The main job: the quick preset of the benchmark matrix (procedural scenes, reduced resolution),
# after verifying every batch's hits against the host reference at the same resolution.
BENCH_SCENES ?= cornell,detail-room,landscape,multi-instance
BENCH_RESOLUTION ?= 320x180
BENCH_OUT ?= results/bench-quick

.PHONY: all deps configure build test bench clean fuzz test-sanitize test-slurm

all: build

deps:
	bash scripts/install-deps.sh

$(BUILD)/CMakeCache.txt:
	cmake -S . -B $(BUILD) $(CMAKE_FLAGS)

configure: $(BUILD)/CMakeCache.txt

build: configure
	cmake --build $(BUILD) -j $(JOBS)

test: deps
	$(MAKE) build
	ctest --test-dir $(BUILD) --output-on-failure -j $(JOBS)

bench: deps
	$(MAKE) build
	$(BUILD)/raysort trace --scene $(BENCH_SCENES) --resolution $(BENCH_RESOLUTION) --max-time 0.3
	@# The default folder is scratch (gitignored) and starts fresh each time: one left by an older
	@# build may hold another matrix configuration, which `run` refuses to resume into. A folder
	@# given as BENCH_OUT=... is never deleted (run resumes into it, or says why it cannot).
	$(if $(filter results/bench-quick,$(BENCH_OUT)),rm -rf results/bench-quick,@true)
	$(BUILD)/raysort run --preset quick --resolution $(BENCH_RESOLUTION) --out $(BENCH_OUT)
	@echo "tables: $(BENCH_OUT)/tables.md"

# libFuzzer targets (fuzz/) for the OBJ loader, the scene parser, the result-set reader and the command
# line, FUZZ_SECONDS each (default 60),
# in build-fuzz with clang (installed from Debian when missing). Findings fail the target.
FUZZ_SECONDS ?= 60
fuzz:
	FUZZ_BUILD=build-fuzz FUZZ_SECONDS=$(FUZZ_SECONDS) JOBS=$(JOBS) bash scripts/fuzz.sh

# The host-side tests under AddressSanitizer + UndefinedBehaviorSanitizer (gcc, build-asan): every
# test binary that needs no OpenCL device, and the device-free tests of bench_test and cli_test.
test-sanitize: deps
	bash scripts/test-sanitize.sh

# Opt-in, not part of `make test` (docs/slurm.md): brings up a one-node Slurm cluster on this
# machine (munge, slurmctld, slurmd from Debian, installed by the script; needs root or sudo), runs
# the quick preset at 48x27 as SLURM_SHARDS shards plus the merge job, and checks the merged result
# against a single-machine run cell for cell. The daemons are stopped on every exit.
SLURM_SHARDS ?= 3
test-slurm: deps
	$(MAKE) build
	bash tests/slurm/slurm-test.sh $(BUILD)/raysort $(SLURM_SHARDS)

clean:
	rm -rf $(BUILD)
