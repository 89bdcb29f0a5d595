# The two commands of README.md: `make demo` and `make test`. Both first run the idempotent
# set-up (Debian and Python packages), then configure with Ninja into build/ and build.
PYTHON ?= python3
BUILD  ?= build
JOBS   ?= $(shell nproc)

.PHONY: setup build demo test clean figures

setup:
	@bash scripts/setup.sh

build: setup
	@cmake -S . -B $(BUILD) -G Ninja -DCMAKE_BUILD_TYPE=Release >/dev/null
	@cmake --build $(BUILD) -j $(JOBS)

# The paper's Fig. 8 scene: one-sweep XPBD stalls where the global direct solve converges.
demo: build
	@mkdir -p results plots
	$(BUILD)/xpbd-bench run --scene cloth_hang --solver xpbd-jacobi,xpbd-gs,jacobi-pcg,cholmod --out results/demo.h5
	$(PYTHON) plots/convergence.py results/demo.h5 -o plots/demo_convergence.png

# The paper's claims (figures/*.toml; FIGURES_SIZE=paper for figures/paper/*.toml): sweeps into
# plots/figures/data/, figures and plots/figures/summary.md. Rerunning resumes unfinished sweeps.
FIGURES_SIZE ?= default
figures: build
	$(PYTHON) plots/figures.py --bench $(BUILD)/xpbd-bench --size $(FIGURES_SIZE)

test: build
	cd $(BUILD) && ctest --output-on-failure -j $(JOBS)

clean:
	rm -rf $(BUILD)
