# The two commands of README.md: `make demo` and `make test`. Both first run the idempotent
# set-up (Debian and Python packages), then configure with Ninja into build/ and build.
PYTHON ?= python3
BUILD  ?= build
JOBS   ?= $(shell nproc)

# OpenMP threads that sleep at barriers instead of spinning: on a shared or loaded machine a
# spinning team waiting for a descheduled thread made solves 10-100x slower (measured: jacobi-pcg
# on cloth_hang 0.15 s passive vs 0.33-31 s active under load). A short spin first (~0.3 ms):
# with none, every parallel region pays a futex wake-up (120 us each here; harness/cli/
# wait_policy.hpp). What build/xpbd-bench sets itself when started without a policy; set either
# yourself to override.
export OMP_WAIT_POLICY ?= passive
export GOMP_SPINCOUNT ?= 10000

.PHONY: setup build demo test test-asan fuzz clean figures race race-scale race-full perf perf-baseline

setup:
	@bash scripts/setup.sh

# The build also writes the Python package xpbd_bench into $(BUILD)/python/ (docs/python.md);
# a .pth file makes the python3 on PATH import it from there.
build: setup
	@cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
	@cmake --build $(BUILD) -j $(JOBS)
	@$(PYTHON) scripts/link_python_package.py $(BUILD)

# The paper's Fig. 8 scene: one-sweep XPBD stalls where the global solves converge; every global
# method in both forms of its linear step (dual A dlambda = b, primal K dx = J^T alpha~^-1 b). Then
# on the truth (--reference): XPBD Gauss-Seidel, VBD and AVBD (400 sweeps) and Newton with CHOLMOD,
# their position error against wall time (plots/demo_truth.png; docs/vbd.md).
demo: build
	@mkdir -p results plots
	$(BUILD)/xpbd-bench run --scene cloth_hang --solver xpbd-jacobi,xpbd-gs,jacobi-pcg,cholmod,mgpbd --form dual,primal --out results/demo.h5
	$(PYTHON) plots/convergence.py results/demo.h5 -o plots/demo_convergence.png
	$(BUILD)/xpbd-bench run --scene cloth_hang --solver xpbd-gs,vbd,avbd --reference --set rtol=0 --set atol=0 --set max_iterations=400 --out results/demo_truth.h5
	$(BUILD)/xpbd-bench run --scene cloth_hang --profile newton --solver cholmod --reference --out results/demo_truth.h5 --append
	$(PYTHON) plots/error_time.py results/demo_truth.h5 -o plots/demo_truth.png

# The paper's claims (figures/*.toml, one spec per figure; FIGURES_SIZE=paper applies each spec's
# [sizes.paper] table): figures/run.py runs the sweeps into
# plots/figures/data/, figures and plots/figures/summary.md. Rerunning resumes unfinished sweeps;
# FIGURES_ARGS="--fresh" starts them again, "--only squash_mgpbd,theta" selects specs.
FIGURES_SIZE ?= default
figures: build
	$(PYTHON) figures/run.py --bench $(BUILD)/xpbd-bench --size $(FIGURES_SIZE) $(FIGURES_ARGS)

# The race on the truth (figures/race/race.toml, docs/race.md): outer methods (XPBD, its two
# variants, Newton; VBD and AVBD with their own sweeps, docs/vbd.md) x linear methods, one process per run, each reading its size's one reference
# (computed once per size); the time to a position error of 1e-2, 1e-3 and 1e-4 against the
# backward-Euler solution, into plots/race/ (race_<scene>.png, summary.md, timings.tsv, plan.txt).
# `race`: one size per scene (the spec's quick_size) and Eisenstat-Walker only; `race-scale`: every
# size (the squash to 1.6M tets, the twist bar to 255K, the cloth to 512^2) with Eisenstat-Walker,
# each entry under a predicted time budget and a memory limit, cut to the spec's plan.total_seconds
# (2 h) of machine time in all; `race-full`: every size and forcing rule, no total. All resume
# (finished runs are kept): run them in parts. RACE_ARGS="--dry-run" prints the plan (each entry's
# predicted time and memory, what is skipped or cut and why) and stops; "--fresh", "--only squash",
# "--outer newton", "--linear mgpbd,cholmod", "--reference-jobs 2" (references first, in parallel).
# Publishing: python3 plots/race.py plots/race/data --out docs/race --readme README.md --pick docs/results/vbd_pick.md
RACE_ARGS ?=
race: build
	$(PYTHON) figures/race.py --bench $(BUILD)/xpbd-bench --quick $(RACE_ARGS)

race-scale: build
	$(PYTHON) figures/race.py --bench $(BUILD)/xpbd-bench --scale $(RACE_ARGS)

race-full: build
	$(PYTHON) figures/race.py --bench $(BUILD)/xpbd-bench $(RACE_ARGS)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

# The whole test suite under AddressSanitizer + UndefinedBehaviorSanitizer (GCC, -O1) in
# build-asan/; the first report fails its test. The options (each one's reason in
# scripts/asan_env.sh) let OpenMPI and OpenMP run under ASan. thread_determinism is left out: it
# runs the code the other tests run, 24 times over, to compare bits, which ASan does not check;
# so is store_kills: it kills the writers of results_store's code paths 103 times to check what
# is on disk, which ASan does not check either.
ASAN_BUILD ?= build-asan
test-asan: setup
	@cmake -S . -B $(ASAN_BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Sanitize -DXB_SANITIZE=ON >/dev/null
	@cmake --build $(ASAN_BUILD) -j $(JOBS)
	. scripts/asan_env.sh && cd $(ASAN_BUILD) && ctest --output-on-failure -j $(JOBS) -E '^(thread_determinism|store_kills)$$'

# libFuzzer targets, one per reader of user files (fuzz/README.md), built with clang into
# build-fuzz/ and run one after the other for FUZZ_SECONDS each, seeded from the test data;
# FUZZ_TARGETS picks some. A finding stops it, with the input under build-fuzz/findings/.
FUZZ_BUILD ?= build-fuzz
FUZZ_SECONDS ?= 60
FUZZ_TARGETS ?= tetgen gmsh medit scene sweep system results system_struct results_struct
fuzz: setup
	@cmake -S . -B $(FUZZ_BUILD) -G Ninja -DCMAKE_C_COMPILER=clang -DCMAKE_CXX_COMPILER=clang++ \
	  -DCMAKE_BUILD_TYPE=Sanitize -DXB_FUZZ=ON -DXB_WITH_HYPRE=OFF -DXB_WITH_MUELU=OFF >/dev/null
	@cmake --build $(FUZZ_BUILD) -j $(JOBS) --target fuzz_all
	bash fuzz/run.sh $(FUZZ_BUILD) $(FUZZ_SECONDS) $(FUZZ_TARGETS)

# CI performance tracking: microbenchmarks + deterministic metrics into
# results/perf/<git-sha>.json, compared with results/baselines/perf.json; fails when an iteration
# count (+10 %) or operator complexity (+2 %) got worse. PERF_FLAGS=--short: the CI gate's form.
PERF_FLAGS ?=
perf: build
	$(PYTHON) scripts/perf.py run --build $(BUILD) $(PERF_FLAGS)

# Rewrites the committed baseline on purpose (commit results/baselines/perf.json afterwards).
perf-baseline: build
	$(PYTHON) scripts/perf.py run --build $(BUILD) --write-baseline

clean:
	rm -rf $(BUILD) $(ASAN_BUILD) $(FUZZ_BUILD)
