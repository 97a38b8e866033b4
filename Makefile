# rtaccel — every entry point. `make run` and `make test` install what they need on a fresh machine.
# under ./rtaccel (RTACCEL_STATUS set) recipes run through tools/recipe-shell, which records a failing line's own
# exit status: make reports any failed recipe as 2
SHELL := $(if $(RTACCEL_STATUS),$(abspath tools/recipe-shell),/bin/bash)
.DEFAULT_GOAL := help

ROOT      := $(abspath .)
PY        := $(ROOT)/.venv/bin/python
SBT       := $(ROOT)/tools/sbt
CP_FILE   := build/classpath.txt
VERSION   := $(shell git describe --always --dirty 2>/dev/null || echo unknown)
JAVA       = java -Xss64m -Xmx8g -Drtaccel.version=$(VERSION) -cp "$$(cat $(CP_FILE))"
export PYTHONPATH := $(ROOT)

# User variables (documented in README.md).
SCENE   ?= build/scenes/cornell.obj
CONFIG  ?= fit
WIDTH   ?= 64
HEIGHT  ?= 48
DEPTH   ?= 5
SEED    ?= 1
SHARED_SCENES ?= $(abspath ../shared/scenes)
RUN_CONFIG ?= paper2017
RUN_NODE_CACHE ?= 8192
# The platform knobs come from the knob registry's export (config/knobs.json, `make knobs`; rtaccel.config.Knobs):
# KNOB_NAMES, each knob's flag KNOB_FLAG_<K> and the targets that read it KNOB_USE_<K>. No knob is spelled here.
build/knobs.mk: config/knobs.json tools/knobs-mk
	@mkdir -p build && python3 tools/knobs-mk $< > $@.tmp && mv $@.tmp $@
include build/knobs.mk
# the flags of the knobs among $(1) that are given
knob_flags = $(foreach k,$(1),$(if $($(k)),$(KNOB_FLAG_$(k)) $($(k))))
# A preset is the whole platform it names (caches included); each knob given overrides one field, an absent one
# keeps the preset's value (README "Configurations").
PLATFORM_KNOBS = $(call knob_flags,$(filter-out CONFIG,$(KNOB_NAMES)))
# A knob given on the command line to a target that does not read it is refused (make would ignore it); the
# targets' own calls of make (MAKELEVEL > 0) pass what they were given on
ifeq ($(MAKELEVEL),0)
KNOBS_UNUSED := $(strip $(foreach g,$(MAKECMDGOALS),$(foreach k,$(KNOB_NAMES),$(if $(filter command line,$(origin $(k))),$(if $(filter $(g),$(KNOB_USE_$(k))),,$(k)=$($(k)) on $(g))))))
ifneq ($(KNOBS_UNUSED),)
$(error $(firstword $(KNOBS_UNUSED)) has no effect on make $(word 3,$(KNOBS_UNUSED)): leave it out; $(firstword $(subst =, ,$(firstword $(KNOBS_UNUSED)))) is read by make $(subst $() ,|,$(KNOB_USE_$(firstword $(subst =, ,$(firstword $(KNOBS_UNUSED)))))))
endif
endif
MODEL_ARGS = $(call knob_flags,CONFIG) $(PLATFORM_KNOBS)
TRIS       = $$(tools/tris $(SCENE))

SCALA_SRC := $(shell find src/main -name '*.scala' 2>/dev/null) build.sbt project/build.properties

.PHONY: help deps venv verilator clang z3 run test test-scala test-python fixtures golden trace cachesim check analyze bench clean \
        yosys verilog area area-fp timing timing-fit cost-model max-tus lint simulate roofline soak regress paper-nocache paper-caches bench-caches dse precision fidelity paper knobs

help:
	@echo "make run | test | golden | trace | cachesim | check | analyze | bench | simulate | roofline | soak | verilog | lint | area | area-fp | timing | timing-fit | cost-model | max-tus | regress | paper-nocache | paper-caches | bench-caches | dse | precision | fidelity | paper | knobs   (see README.md)"

# ---------------------------------------------------------------- installation
# The venv (pip, mostly downloads) and the Scala compile (scalac, one core) install side by side.
deps: verilator clang
	@$(MAKE) -s --no-print-directory -j2 venv $(CP_FILE)

venv: .venv/.stamp
.venv/.stamp: requirements.txt
	@echo "[deps] python venv (.venv) from requirements.txt"
	python3 -m venv .venv
	.venv/bin/pip install -q --disable-pip-version-check -r requirements.txt
	touch $@

# The C++ compiler of the simulators Verilator builds (the test suites' through build.sbt, make simulate's through
# sim.VerilatorBuild.compiler), chosen here once: clang compiles a model at -O0 in about 0.63 of g++'s time, and the
# test suites' simulators are mostly that compile. RTACCEL_CXX=g++ keeps Verilator's default.
# tools/cxx-pch runs it with Verilator's header precompiled (about half a model build's compile time).
export RTACCEL_CXX_REAL ?= $(shell command -v clang++-14 || command -v clang++)
export RTACCEL_CXX ?= $(if $(RTACCEL_CXX_REAL),$(ROOT)/tools/cxx-pch,g++)
clang:
	@command -v clang++-14 >/dev/null || command -v clang++ >/dev/null || { echo "[deps] installing clang-14 from apt"; \
	  S=$$( [ "$$(id -u)" = 0 ] || echo sudo ); $$S apt-get update -qq && $$S apt-get install -y -qq clang-14 >/dev/null; }

verilator:
	@command -v verilator >/dev/null || { echo "[deps] installing verilator from apt"; \
	  S=$$( [ "$$(id -u)" = 0 ] || echo sudo ); $$S apt-get update -qq && $$S apt-get install -y -qq verilator >/dev/null; }

# Yosys reads the emitted Verilog in make test (and synthesizes it in make area).
yosys:
	@command -v yosys >/dev/null || { echo "[deps] installing yosys from apt"; \
	  S=$$( [ "$$(id -u)" = 0 ] || echo sudo ); $$S apt-get update -qq && $$S apt-get install -y -qq yosys >/dev/null; }

# The bounded proofs of src/test/scala/**/*FormalSpec.scala (docs/formal.md) run on Yices 2 (yices-smt2, in the venv
# from requirements.txt). z3 and CVC4 from apt only to compare engines: RTACCEL_FORMAL_ENGINE=z3|cvc4 make regress.
# The test JVM finds yices-smt2 on PATH.
TEST_PATH = PATH=$(ROOT)/.venv/bin:$$PATH
z3:
	@command -v z3 >/dev/null && command -v cvc4 >/dev/null || { echo "[deps] installing z3 and cvc4 from apt"; \
	  S=$$( [ "$$(id -u)" = 0 ] || echo sudo ); $$S apt-get update -qq && $$S apt-get install -y -qq z3 cvc4 >/dev/null; }

# Compiles the Scala side and records its runtime classpath so entry points start as plain `java`.
$(CP_FILE): $(SCALA_SRC)
	@mkdir -p build
	@echo "[deps] compiling Scala (sbt launcher from Maven Central on first use)"
	$(SBT) compile "export Runtime/fullClasspath" | tee build/sbt-export.log | grep -E '^\[(error|warn)' || true
	@tail -n 1 build/sbt-export.log | grep -q '^/' || { echo "error: Scala compile failed; see build/sbt-export.log" >&2; exit 1; }
	tail -n 1 build/sbt-export.log > $@

build/scenes/%.obj: | venv
	@mkdir -p build/scenes
	$(PY) -m scenes.procedural $* $@

# ---------------------------------------------------------------- main job
run: deps build/scenes/cornell.obj
	@mkdir -p build/run
	@$(MAKE) --no-print-directory golden SCENE=$(SCENE) OUT=build/run/golden
	@set -o pipefail; $(MAKE) --no-print-directory check SCENE=$(SCENE) GOLDEN=build/run/golden | tee build/run/check.log
	@set -o pipefail; $(MAKE) --no-print-directory analyze SCENE=$(SCENE) GOLDEN=build/run/golden OUT=build/run/analysis | tee build/run/analyze.log
	@set -o pipefail; $(MAKE) --no-print-directory simulate SCENE=$(SCENE) GOLDEN=build/run/golden CONFIG=$(RUN_CONFIG) NODE_CACHE=$(RUN_NODE_CACHE) OUT=build/run/simulate | tee build/run/simulate.log
	@$(PY) -m dse.studies.run_summary build/run

# ---------------------------------------------------------------- user commands
golden: venv
	@test -n "$(OUT)" || { echo "error: give OUT=<dir> for the golden trace" >&2; exit 2; }
	@mkdir -p $(dir $(abspath $(OUT)))
	$(PY) -m golden.export --scene $(SCENE) --out $(OUT) --width $(WIDTH) --height $(HEIGHT) --depth $(DEPTH) --seed $(SEED)

# With GOLDEN=<dir of make golden> (rays from its camera frame), OUT also gets image.png and diff.png.
IMAGE = if [ -n "$(GOLDEN)" ] && [ -f "$$OUT/hits.npy" ]; then \
	  $(PY) -m golden.image --tris "$$T" --golden $(GOLDEN) --hits $$OUT/hits.npy --out $$OUT > $$OUT/image.json || exit $$?; \
	  echo "[image] $$OUT/image.png (hits), $$OUT/diff.png (vs Embree)" >&2; fi
RAYS_OR_GOLDEN = R=$(RAYS); if [ -z "$$R" ]; then [ -n "$(GOLDEN)" ] || { echo "error: give RAYS=<rays.npy> or GOLDEN=<dir>" >&2; exit 2; }; R=$(GOLDEN)/rays.npy; fi
trace: deps
	@test -n "$(OUT)" || { echo "error: give OUT=<dir>" >&2; exit 2; }
	@$(RAYS_OR_GOLDEN); OUT=$(OUT); T=$(TRIS) && \
	  $(JAVA) rtaccel.cli.Trace --tris "$$T" --scene-label $(SCENE) --rays $$R --out $$OUT $(MODEL_ARGS) && $(IMAGE)

# Node/primitive cache models on the traversal's accesses (docs/caches.md). Last stdout line: JSON.
CACHE_ARGS = $(if $(SWEEP),--sweep-out $(SWEEP)) $(EXTRA_CACHESIM)
cachesim: deps
	@$(RAYS_OR_GOLDEN); \
	  T=$(TRIS) && $(JAVA) rtaccel.cli.CacheSim --tris "$$T" --scene-label $(SCENE) --rays $$R $(MODEL_ARGS) $(CACHE_ARGS)

check: deps
	@test -n "$(GOLDEN)" || { echo "error: give GOLDEN=<dir made by make golden>" >&2; exit 2; }
	@T=$(TRIS) && O=$$(mktemp -d build/check.XXXXXX) && trap "rm -rf $$O" EXIT && \
	  $(JAVA) rtaccel.cli.Trace --tris "$$T" --scene-label $(SCENE) --rays $(GOLDEN)/rays.npy --out $$O --access-trace 0 $(MODEL_ARGS) >/dev/null && \
	  $(PY) -m golden.check --tris "$$T" --golden $(GOLDEN) --hits $$O/hits.npy --summary $$O/summary.json $(if $(REPORT_ONLY),--report-only)

analyze: deps
	@OUT=$${OUT:-build/analyze/$$(basename $(SCENE))}; G=$(GOLDEN); \
	  if [ -z "$$G" ]; then G=$$OUT/golden; $(MAKE) --no-print-directory golden SCENE=$(SCENE) OUT=$$G >&2 || exit $$?; fi; \
	  T=$(TRIS) && $(JAVA) rtaccel.cli.Analyze --tris "$$T" --scene-label $(SCENE) --rays $$G/rays.npy --out $$OUT $(MODEL_ARGS) && \
	  $(PY) -m dse.plots.analysis $$OUT >&2 && echo "[analyze] CSV and PNG in $$OUT" >&2

# Every numerics option on one set of rays (docs/numerics.md, "The trade, measured"): accuracy against Embree and
# the fp32 baseline, lost hits, traversal work, DRAM bytes per ray, RTL rays/s (PRECISION_RTL=0 skips it) and the
# IU's synthesized cost (PRECISION_AREA=yosys; empty otherwise). OUT/precision.csv + .png, default OUT
# build/precision/<scene>; exit 3 when an option's RTL check failed.
PRECISION_OPTIONS ?= fp32:mt fp24:mt fp16:mt bf16:mt fp32:watertight fp24:watertight fp16:watertight bf16:watertight
PRECISION_RTL ?= 1
PRECISION_AREA ?= none
PRECISION_EXHAUSTIVE ?= 1000
precision: TUS ?= 32
precision: NODE_CACHE ?= 8192
precision: deps
	@test -f "$(SCENE)" || { echo "error: scene '$(SCENE)' not found; give SCENE=<path to .obj or .ply>" >&2; exit 2; }
	@OUT=$${OUT:-build/precision/$$(basename $(SCENE) | sed 's/\.[a-z]*$$//')}; G=$(GOLDEN); mkdir -p $$OUT; \
	  if [ -z "$$G" ]; then G=$$OUT/golden; [ -f $$G/rays.npy ] || $(MAKE) --no-print-directory golden SCENE=$(SCENE) OUT=$$G >&2 || exit $$?; fi; \
	  T=$(TRIS) && $(PY) -m dse.studies.precision --scene $(SCENE) --tris "$$T" --golden $$G --out $$OUT --java '$(JAVA)' \
	    --knobs "$(MODEL_ARGS)" --options "$(PRECISION_OPTIONS)" --rtl $(PRECISION_RTL) --area $(PRECISION_AREA) \
	    --exhaustive $(PRECISION_EXHAUSTIVE) $(call knob_flags,BOARD)

# The loop every multi-scene target shares: for each mesh s of $(1) (absent: skipped with a note naming
# $(2), or an error when $(6) is "strict"), n = its name, G = $(3); the golden frame $(4) x $(5) (DEPTH, SEED)
# is made in G unless G/rays.npy exists and is newer than the mesh. The commands after the call see s, n, G
# and end with `done`.
SCENE_LOOP = for s in $(1); do \
	  if [ ! -f "$$s" ]; then $(if $(filter strict,$(6)),echo "error: scene '$$s' not found; give SCENE=<path to .obj or .ply>" >&2; exit 2,echo "[$(2)] skip $$s (absent)"; continue); fi; \
	  n=$$(basename $$s .obj); n=$$(basename $$n .ply); G=$(3); \
	  [ "$$G/rays.npy" -nt "$$s" ] || $(MAKE) --no-print-directory golden SCENE=$$s OUT=$$G WIDTH=$(4) HEIGHT=$(5) >/dev/null || exit $$?;

BENCH_SCENES ?= $(SHARED_SCENES)/sponza_dabrovic.obj $(SHARED_SCENES)/conference.obj
bench: deps
	@$(call SCENE_LOOP,$(BENCH_SCENES),bench,build/bench/$$n/golden,128,96) \
	  T=$$(tools/tris $$s); \
	  $(JAVA) rtaccel.cli.Bench --tris "$$T" --scene-label $$s --rays $$G/rays.npy $(MODEL_ARGS) > build/bench/$$n/model.json || exit $$?; \
	  $(PY) -m golden.bench --scene $$s --rays $$G/rays.npy > build/bench/$$n/embree.json || exit $$?; \
	  $(PY) -m dse.studies.bench_table $$n build/bench/$$n/model.json build/bench/$$n/embree.json; \
	done

# The cache model against the RTL on the same rays and caches at BENCH_CACHE_TUS (docs/caches.md): miss rates,
# rays/s vs the model's bandwidth bound, wall time per ray. Per scene: build/bench-caches/<scene>-node<N>/{*.json,bench.csv}.
BENCH_CACHE_TUS ?= 1 8 32
BENCH_NODE_CACHE ?= 8192
bench-caches: deps
	@set -o pipefail; $(call SCENE_LOOP,$(BENCH_SCENES),bench-caches,build/bench-caches/$$n/golden,32,24) \
	  d=build/bench-caches/$$n-node$(BENCH_NODE_CACHE); mkdir -p $$d; \
	  for t in $(BENCH_CACHE_TUS); do echo "[bench-caches] $$n TUS=$$t" >&2; \
	    $(MAKE) --no-print-directory simulate SCENE=$$s GOLDEN=$$G CONFIG=paper2017 TUS=$$t NODE_CACHE=$(BENCH_NODE_CACHE) OUT=$$d/sim-tu$$t \
	      | tail -n 1 > $$d/sim-tu$$t.json || exit $$?; \
	    $(MAKE) --no-print-directory cachesim SCENE=$$s GOLDEN=$$G CONFIG=paper2017 TUS=$$t NODE_CACHE=$(BENCH_NODE_CACHE) EXTRA_CACHESIM="--repeat 5" \
	      | tail -n 1 > $$d/model-tu$$t.json || exit $$?; done; \
	  $(PY) -m dse.studies.bench_caches $$d/bench.csv $$n $$d || exit $$?; done

# ---------------------------------------------------------------- RTL
VCONFIG = $(if $(filter fit,$(CONFIG)),paper2017,$(CONFIG))
verilog: deps
	$(JAVA) rtaccel.cli.EmitVerilog --config $(VCONFIG) $(PLATFORM_KNOBS) --out build/$(VCONFIG)

# FPGA resources from a Yosys synthesis (docs/area.md): table on stderr, JSON last line; exit 3 when the
# configuration does not fit BOARD. Cached per circuit in build/area-cache.
area: deps yosys
	@$(JAVA) rtaccel.cli.Area --config $(VCONFIG) $(PLATFORM_KNOBS) \
	  $(if $(FIDELITY),--fidelity $(FIDELITY)) $(if $(UNIT),--unit $(UNIT)) $(if $(OUT),--out $(OUT))

# Routed timing on an ECP5 board (docs/area.md "Routed timing"): yowasp synth_ecp5 + nextpnr-ecp5 (from .venv) of
# the board top or UNIT=<module> in a shift-register wrapper; JSON last line, timing.json + nextpnr log in OUT
# (default build/timing/<config>-<board>[-<unit>]); exit 3 when fmax < CLOCK_MHZ (else the board's clock) or the
# design does not fit. Cached per circuit and seed in build/timing-cache. SPEED=6|7|8 overrides the part's grade;
# TIMING_ROUTER=router2 routes with nextpnr's other router; TIMING_PLACER=static|sa places with another placer.
TIMING_SEEDS ?= 1
timing: deps
	@$(JAVA) rtaccel.cli.TimingCmd --config $(VCONFIG) $(PLATFORM_KNOBS) --seeds $(TIMING_SEEDS) \
	  $(if $(UNIT),--unit $(UNIT)) $(if $(SPEED),--speed $(SPEED)) $(if $(TIMING_ROUTER),--router $(TIMING_ROUTER)) \
	  $(if $(TIMING_PLACER),--placer $(TIMING_PLACER)) $(if $(OUT),--out $(OUT))

# The ecp5 rule of the timing proxy fitted to every route in build/timing-cache (docs/area.md "Routed timing"):
# each route's proxy levels and routed clock against the fitted rule and the current one; WRITE=1 puts the fit
# into boards/timing.json. JSON last line; exit 2 when too few routes are cached to fit.
timing-fit: deps
	@$(JAVA) rtaccel.cli.TimingFit $(if $(WRITE),--write $(WRITE)) $(if $(TIMING_CACHE),--cache $(TIMING_CACHE))

# The fitted cost model (FIDELITY=model) from the syntheses of boards/cost-calibration.json (cached per circuit);
# writes boards/cost-model.json with its error on the validation configurations.
cost-model: deps yosys
	@$(JAVA) rtaccel.cli.CostFit --calibration boards/cost-calibration.json --out $(or $(OUT),boards/cost-model.json) \
	  $(if $(CACHED_ONLY),--cached-only $(CACHED_ONLY))

# Largest TU count that fits BOARD (cost model), confirmed by one synthesis (CONFIRM=0 skips it).
max-tus: deps yosys
	@$(JAVA) rtaccel.cli.MaxTus --config $(VCONFIG) $(PLATFORM_KNOBS) $(if $(CONFIRM),--confirm $(CONFIRM)) $(if $(OUT),--out $(OUT))

# Each fp32 operation of src/main/scala/rtaccel/fp alone between flip-flops for BOARD's family (docs/area.md), at its
# fixed depth and at the depth PIPELINE (default auto) gives at CLOCK_MHZ (default the board's): table on stderr,
# JSON last line; cached like make area.
area-fp: deps yosys
	@$(JAVA) rtaccel.cli.AreaFp $(call knob_flags,BOARD CATALOG PIPELINE CLOCK_MHZ) $(if $(OPS),--ops $(OPS)) $(if $(OUT),--out $(OUT))

# Lint waivers, each with its reason, are in tools/lint.vlt.
LINT_WAIVERS = tools/lint.vlt
lint: verilog verilator
	verilator --lint-only -Wall $(LINT_WAIVERS) --top-module RtAccelTop build/$(VCONFIG)/*.sv && echo "[lint] build/$(VCONFIG): verilator -Wall clean"

SIM_ARGS = $(if $(MEM_JITTER),--mem-jitter $(MEM_JITTER)) $(if $(HOST_STALL),--host-stall $(HOST_STALL)) \
  $(if $(MEM_ERROR_RATE),--mem-error-rate $(MEM_ERROR_RATE)) $(if $(MEM_ERROR_MODE),--mem-error-mode $(MEM_ERROR_MODE)) $(if $(WAVES),--waves $(WAVES)) \
  $(if $(WAVES_FROM),--waves-from $(WAVES_FROM)) $(if $(WAVES_TO),--waves-to $(WAVES_TO)) $(if $(SIM_BUILD),--sim-build $(SIM_BUILD))
# Exit status: 0 every check held, 2 bad input, 3 ran but a check failed (the JSON line and outputs remain).
simulate: deps
	@$(RAYS_OR_GOLDEN); OUT=$${OUT:-build/simulate/$$(basename $(SCENE))}; T=$(TRIS) || exit $$?; \
	  $(JAVA) rtaccel.cli.Simulate --tris "$$T" --scene-label $(SCENE) --rays $$R --out $$OUT $(MODEL_ARGS) $(SIM_ARGS); rc=$$?; \
	  if [ $$rc -eq 0 ] || [ $$rc -eq 3 ]; then $(IMAGE); fi; exit $$rc

# The roofline of RTL runs (docs/roofline.md): achieved rays/s against the memory bound (sustained bandwidth / DRAM
# bytes per ray after the caches) and the compute bound (IU beats per cycle / beats per ray), for the knobs given
# or for each TU count of ROOFLINE_TUS with each IU count of ROOFLINE_IUS (a grid). Without GOLDEN, a ROOFLINE_WIDTH x ROOFLINE_HEIGHT frame with DEPTH bounces
# is made (and kept) in build/roofline/<scene>/golden/. OUT/roofline.csv + roofline.png; JSON last line.
ROOFLINE_TUS ?=
ROOFLINE_IUS ?=
ROOFLINE_WIDTH ?= 128
ROOFLINE_HEIGHT ?= 96
roofline: deps
	@s=$(SCENE); [ -f "$$s" ] || { echo "error: scene '$$s' not found; give SCENE=<path to .obj or .ply>" >&2; exit 2; }; \
	  n=$$(basename $$s .obj); n=$$(basename $$n .ply); OUT=$${OUT:-build/roofline/$$n}; \
	  if [ -n "$(GOLDEN)" ]; then G=$(GOLDEN); [ -f "$$G/rays.npy" ] || { echo "error: GOLDEN=$$G has no rays.npy; give a folder made by make golden" >&2; exit 2; }; \
	  else G=build/roofline/$$n/golden/$(ROOFLINE_WIDTH)x$(ROOFLINE_HEIGHT)-d$(DEPTH)-s$(SEED); \
	    [ "$$G/rays.npy" -nt "$$s" ] || $(MAKE) --no-print-directory golden SCENE=$$s OUT=$$G WIDTH=$(ROOFLINE_WIDTH) HEIGHT=$(ROOFLINE_HEIGHT) >/dev/null || exit $$?; fi; \
	  T=$$(tools/tris $$s) || exit $$?; \
	  J=$$($(JAVA) rtaccel.cli.RooflineCmd --tris "$$T" --scene-label $$s --rays $$G/rays.npy --out $$OUT $(MODEL_ARGS) \
	    $(if $(strip $(ROOFLINE_TUS)),--tus-list "$(strip $(ROOFLINE_TUS))") $(if $(strip $(ROOFLINE_IUS)),--ius-list "$(strip $(ROOFLINE_IUS))") $(if $(SIM_BUILD),--sim-build $(SIM_BUILD)) | tail -n 1; exit $${PIPESTATUS[0]}); rc=$$?; \
	  if [ $$rc -ne 0 ]; then [ -z "$$J" ] || echo "$$J"; exit $$rc; fi; \
	  $(PY) -m dse.plots.roofline $$OUT/roofline.png $$OUT/roofline.csv || exit $$?; echo "$$J"

# At least RAYS_N rays (a 1000-wide camera frame of the embedded room) through the RTL in one run, with random
# DRAM latency and host backpressure: 0 lost, 0 duplicated, 0 mismatches, or exit 3. A benchmark, not a test.
RAYS_N ?= 1000000
soak: deps build/scenes/cornell.obj
	@H=$$(( ($(RAYS_N) + 999) / 1000 )); G=build/soak/golden-1000x$$H; \
	  [ -f $$G/rays.npy ] || $(MAKE) --no-print-directory golden SCENE=build/scenes/cornell.obj OUT=$$G WIDTH=1000 HEIGHT=$$H DEPTH=0 >/dev/null || exit $$?; \
	  $(MAKE) --no-print-directory simulate SCENE=build/scenes/cornell.obj GOLDEN=$$G CONFIG=$(RUN_CONFIG) \
	    MEM_JITTER=$(or $(MEM_JITTER),23) HOST_STALL=$(or $(HOST_STALL),20) OUT=build/soak/simulate
# Every suite with every variant (rtaccel.Regress.full): make test's cases and the ones it leaves out. REGRESS_ONLY=
# names suites to run alone, e.g. REGRESS_ONLY="rtaccel.top.PlatformSpec rtaccel.iu.IuPipesSpec".
regress: deps yosys fixtures
	$(TEST_PATH) RTACCEL_REGRESS=full RTACCEL_FIXTURES=$(ROOT)/build/fixtures $(SBT) $(if $(REGRESS_ONLY),"testOnly $(REGRESS_ONLY)",test)

# Paper Figs 12-13 without cache: rays/s and memory utilisation vs TUs (CSV + PNG in build/paper-nocache).
NOCACHE_SCENES ?= $(SHARED_SCENES)/sponza_dabrovic.obj $(SHARED_SCENES)/conference.obj
NOCACHE_TUS ?= 1,2,4,8,16,32
# Figs 4, 8-9, 11-13 are drawn at the paper's M and MPPL unless given
paper-nocache paper-caches: M ?= 4
paper-nocache paper-caches: MPPL ?= 4
paper-nocache: deps
	@mkdir -p build/paper-nocache; csvs=""; $(call SCENE_LOOP,$(NOCACHE_SCENES),paper-nocache,build/paper-nocache/$$n/golden,32,24) \
	  d=build/paper-nocache/$$n; \
	  T=$$(tools/tris $$s); $(JAVA) rtaccel.cli.SweepTus --tris "$$T" --scene-label $$s --rays $$d/golden/rays.npy --out $$d \
	    --config paper2017 --node-cache 0 $(call knob_flags,M MPPL) --tus-list $(NOCACHE_TUS) || exit $$?; csvs="$$csvs $$d/tus_sweep.csv"; done; \
	  [ -z "$$csvs" ] || $(PY) -m dse.plots.tus build/paper-nocache/tus_sweep.png $$csvs

# Paper Figs 11 (node-cache miss rate vs size) and 8-9 (DRAM bytes per ray vs MPPL) from the cache model, and
# Figs 12-13 with the 2^13-entry DM node cache from the RTL (slow; skip with PAPER_TUS=). CSV + PNG per scene in
# build/paper-caches/<scene>/, combined PNGs in build/paper-caches/ (dse/paper/caches.py, docs/caches.md).
# SCENE=<mesh> on the command line runs just that scene. The golden rays are kept per resolution, depth and seed
# in <scene>/golden/ and remade only when absent or older than the mesh.
PAPER_SCENES ?= $(SHARED_SCENES)/sponza_dabrovic.obj $(SHARED_SCENES)/conference.obj
PAPER_WIDTH  ?= 128
PAPER_HEIGHT ?= 96
PAPER_TUS    ?= 1,2,4,8,16,32
# the RTL sweep uses a smaller frame (as paper-nocache, so the two sweeps share their rays)
PAPER_TUS_WIDTH  ?= 32
PAPER_TUS_HEIGHT ?= 24
PAPER_RUN_SCENES = $(if $(filter command line,$(origin SCENE)),$(SCENE),$(PAPER_SCENES))
paper-caches: deps
	@mkdir -p build/paper-caches; f11=""; f89=""; tus=""; \
	$(call SCENE_LOOP,$(PAPER_RUN_SCENES),paper-caches,build/paper-caches/$$n/golden/$(PAPER_WIDTH)x$(PAPER_HEIGHT)-d$(DEPTH)-s$(SEED),$(PAPER_WIDTH),$(PAPER_HEIGHT),$(if $(filter command line,$(origin SCENE)),strict)) \
	  d=build/paper-caches/$$n; \
	  GT=$$d/golden/$(PAPER_TUS_WIDTH)x$(PAPER_TUS_HEIGHT)-d$(DEPTH)-s$(SEED); \
	  [ -z "$(PAPER_TUS)" ] || [ "$$GT/rays.npy" -nt "$$s" ] || $(MAKE) --no-print-directory golden SCENE=$$s OUT=$$GT WIDTH=$(PAPER_TUS_WIDTH) HEIGHT=$(PAPER_TUS_HEIGHT) >/dev/null || exit $$?; \
	  T=$$(tools/tris $$s) || exit $$?; \
	  $(PY) -m dse.paper.caches --scene $$s --tris "$$T" --rays $$G/rays.npy $$( [ -z "$(PAPER_TUS)" ] || echo --tus-rays $$GT/rays.npy) --out $$d --java '$(JAVA)' $(call knob_flags,M MPPL) \
	    --tus-list "$(PAPER_TUS)" --nocache-csv build/paper-nocache/$$n/tus_sweep.csv || exit $$?; \
	  f11="$$f11 $$d/fig11_miss_rate.csv"; f89="$$f89 $$d/fig8_9_bytes_per_ray.csv"; \
	  [ -z "$(PAPER_TUS)" ] || tus="$$tus $$d/tus_sweep.csv $$( [ -f build/paper-nocache/$$n/tus_sweep.csv ] && echo build/paper-nocache/$$n/tus_sweep.csv)"; done; \
	  [ -z "$$f11" ] || { $(PY) -m dse.plots.caches fig11 build/paper-caches/fig11_miss_rate.png $$f11 && \
	    $(PY) -m dse.plots.caches bytes build/paper-caches/fig8_9_bytes_per_ray.png $$f89; } || exit $$?; \
	  [ -z "$$tus" ] || $(PY) -m dse.plots.tus build/paper-caches/fig12_13_tus.png $$tus

# The paper reproduced (docs/results.md "make paper"): Figs 4, 5-6, 8, 9, 11, 12-13 with and without cache, Table 2
# and Fig 15 on SCENES, each of our numbers beside the paper's, in OUT/report.md (default build/paper) with its
# PNGs. Runs paper-nocache, paper-caches, analyze, roofline (Table 2: paper2017, PAPER_TABLE2_TUS, 2^13 DM, at
# 150 MHz and again at CLOCK_MHZ=fmax after make area of that circuit) and bench per scene (dse/paper/paper.py); a rerun
# reuses every step whose outputs are unchanged (OUT/paper.sqlite). PAPER_TUS="" skips the TU sweeps,
# PAPER_TABLE2_TUS=0 the Table 2 RTL runs, PAPER_TABLE2_FMAX=0 the reached-clock run, PAPER_BENCH=0 Embree; MACHINE_GBPS
# sets this machine's bandwidth for Fig 15 (default: measured). Absent scenes are skipped; none: the embedded room.
SCENES ?= $(SHARED_SCENES)/sponza_dabrovic.obj $(SHARED_SCENES)/conference.obj
PAPER_TABLE2_TUS ?= 32
PAPER_TABLE2_FMAX ?= 1
PAPER_BENCH ?= 1
paper: deps build/scenes/cornell.obj
	@$(PY) -m dse.paper.paper --scenes "$(SCENES)" --fallback build/scenes/cornell.obj --out $(or $(OUT),build/paper) \
	  --version $(VERSION) --tus "$(PAPER_TUS)" --table2-tus $(PAPER_TABLE2_TUS) --table2-fmax $(PAPER_TABLE2_FMAX) --bench $(PAPER_BENCH) \
	  --width $(PAPER_WIDTH) --height $(PAPER_HEIGHT) --tus-width $(PAPER_TUS_WIDTH) --tus-height $(PAPER_TUS_HEIGHT) \
	  --depth $(DEPTH) --seed $(SEED) $(if $(MACHINE_GBPS),--machine-gbps $(MACHINE_GBPS)) --make "$(MAKE)"

# Design-space exploration (docs/dse.md): the points of SPACE=<space file> evaluated on WORKERS Ray workers, each
# keeping one JVM (rtaccel.cli.Serve) between points; a local Ray instance unless RAY_ADDRESS names a cluster.
# Results, CSV, plots and the SQLite store in OUT (default build/dse/<space>); a rerun evaluates only what is missing.
WORKERS ?= 2
DSE_HEAP ?= 3g
DSE_JAVA = java -Xss64m -Xmx$(DSE_HEAP) -Drtaccel.version=$(VERSION) -cp "$$(cat $(ROOT)/$(CP_FILE))"
dse: deps
	@test -n "$(SPACE)" || { echo "error: give SPACE=<space file>, e.g. SPACE=dse/spaces/smoke.toml" >&2; exit 2; }
	@$(PY) -m dse.explore.explore --space $(SPACE) --workers $(WORKERS) $(if $(RAY_ADDRESS),--ray-address $(RAY_ADDRESS)) \
	  $(if $(OUT),--out $(OUT)) --java '$(DSE_JAVA)' --version $(VERSION)

# The speed-for-accuracy ladder (docs/dse.md): every rung of make dse on a fixed grid (FIDELITY_TUS x FIDELITY_CACHES
# x FIDELITY_MPPLS) x FIDELITY_SCENES (sponza, conference: from SHARED_SCENES, skipped when absent; procedural names;
# mesh paths), each cheap figure against the RTL. build/fidelity/fidelity.csv + .png + .md + store.sqlite (a rerun
# evaluates only what is missing); JSON last line; exit 3 when a run failed its check.
FIDELITY_SCENES ?= sponza,conference,hairball
FIDELITY_TUS    ?= 1,2,4,8,16,32
FIDELITY_CACHES ?= none,dm,lrp,hybrid
FIDELITY_MPPLS  ?= 4,8
FIDELITY_NODE_CACHE ?= 8192
FIDELITY_WIDTH  ?= 32
FIDELITY_HEIGHT ?= 24
FIDELITY_DEPTH  ?= 5
FIDELITY_WORKERS ?= 1
fidelity: deps
	@RTACCEL_SHARED_SCENES=$(SHARED_SCENES) $(PY) -m dse.studies.fidelity --scenes "$(FIDELITY_SCENES)" --tus "$(FIDELITY_TUS)" \
	  --caches "$(FIDELITY_CACHES)" --mppls "$(FIDELITY_MPPLS)" --node-cache $(FIDELITY_NODE_CACHE) \
	  --width $(FIDELITY_WIDTH) --height $(FIDELITY_HEIGHT) --depth $(FIDELITY_DEPTH) --seed $(SEED) \
	  --workers $(FIDELITY_WORKERS) --out build/fidelity --java '$(DSE_JAVA)' --version $(VERSION)

# The knob registry (rtaccel.config.Knobs) exported to config/knobs.json, which this Makefile and dse/ read; run it
# after changing a knob (KnobsSpec fails while the file differs from the registry).
knobs: deps
	@$(JAVA) rtaccel.cli.KnobsCmd --out config/knobs.json

# ---------------------------------------------------------------- tests
FIXTURE_SCENES := cornell hairball soup extreme
FIXTURES := build/fixtures/.stamp
fixtures: $(FIXTURES)
$(FIXTURES): $(wildcard scenes/*.py golden/*.py) | venv
	@echo "[test] procedural scenes and golden traces in build/fixtures"
	@set -e; for s in $(FIXTURE_SCENES); do d=build/fixtures/$$s; mkdir -p $$d; \
	  $(PY) -m scenes.procedural $$s $$d/scene.obj; \
	  $(PY) -m scenes.export $$d/scene.obj $$d/tris.npy; \
	  $(PY) -m golden.export --scene $$d/scene.obj --out $$d/golden --width 32 --height 24 --depth 3 --seed 7 >/dev/null; done
	touch $@

# The Python tests start a JVM for each model run of a few hundred rays: the C1 compiler alone and the serial
# collector cut their CPU time by 30 % (231 -> 161 s user for golden/ and dse/, 199 -> 174 s wall). They run on
# every core (pytest-xdist, each worker taking the next test when it is free: a few take 20-30 s), and they run
# beside sbt, which leaves a core idle while scalac compiles the test sources and while its last suites finish;
# their log is printed when both are done. They share no output folder with each other or with the Scala tests.
TEST_JVM = -XX:TieredStopAtLevel=1 -XX:+UseSerialGC
PYTEST_LOG = build/test-reports/python/pytest.log
test: deps yosys fixtures
	@rm -rf build/test-reports; mkdir -p build/test-reports/python
	@rc=0; echo "[test] pytest runs beside sbt (its log, printed at the end: $(PYTEST_LOG))"; \
	RTACCEL_FIXTURES=$(ROOT)/build/fixtures RTACCEL_CLASSPATH=$(ROOT)/$(CP_FILE) RTACCEL_SHARED_SCENES=$(SHARED_SCENES) \
	  JAVA_TOOL_OPTIONS="$(TEST_JVM)" $(PY) -m pytest -q -n auto --dist worksteal --junitxml=build/test-reports/python/pytest.xml \
	  > $(PYTEST_LOG) 2>&1 & py=$$!; trap 'kill $$py 2>/dev/null; exit 130' INT TERM; \
	$(TEST_PATH) RTACCEL_FIXTURES=$(ROOT)/build/fixtures $(SBT) test || rc=3; \
	wait $$py || rc=3; cat $(PYTEST_LOG); \
	$(PY) tools/count_tests.py --failures build/test-reports; exit $$rc

clean:
	rm -rf build target project/target
