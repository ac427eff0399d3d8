# saarsim: cycle-level simulator of a SaarCOR-style ray-tracing chip.
#
#   make            build everything (installs missing Debian packages first)
#   make run        render the embedded default scene and print the report
#   make test       build and run the Criterion test suite
#   make bench      benchmarks; writes docs/PERFORMANCE.md
#   make bench-profile  cycle mode under callgrind, top functions (PERFORMANCE.md)
#   make bench-scale    the largest scene: memory and build time (PERFORMANCE.md)
#   make bench-sampled  a sampled run's time with its defaults (PERFORMANCE.md)
#   make bench-ratio    cycle mode against kernel-ref on every view at 1024x768 (PERFORMANCE.md)
#   make bench-footprint the chip on a packet-footprint kd-tree against its default (PERFORMANCE.md)
#   make bench-frontier sampled mode's speed against its fps error, setting by setting (PERFORMANCE.md)
#   make calibrate  fit the assumed parameters to published figures; writes
#                   docs/CALIBRATION.md (docs/calibration.md)
#   make accel      kd-tree, uniform grid and two-level trees compared;
#                   writes docs/ACCEL.md (scripts/accel.sh)
#   make mutate     mutation tests: each tests/mutants/ patch must be caught
#                   by the tests it names (docs/TESTING.md)
#   make extend-check  docs/extending.md's unit-kind walk-through built and
#                   run in a scratch copy (tests/extend/, docs/TESTING.md)
#   make install    install binaries into $(PREFIX)/bin
#   make SANITIZE=1 test   the same under ASan/UBSan (build-san/)
#   make fuzz-smoke libFuzzer harnesses, each run briefly (docs/TESTING.md)
#
# One static library (libsaar.a) holds kernel-ref and the chip model; the
# programs and the test binary link against it. OpenImageIO lives in a
# plugin, libsaar-oiio.so, opened on the first image read or write
# (kernel-ref/image_plugin.h says why).

.DEFAULT_GOAL := all
PREFIX   ?= /usr/local
CC       ?= cc
CXX      ?= c++
PKGS     := assimp yaml-0.1 zlib
# OpenImageIO is linked only into the image plugin, libsaar-oiio.so, which
# the programs open on their first image read or write (kernel-ref/image_plugin.h).
IMGPKGS  := OpenImageIO
TESTPKGS := criterion

ifeq ($(SANITIZE),1)
B        ?= build-san
SANFLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
OPT      := -O1 -g
else
B        ?= build
SANFLAGS :=
OPT      := -O2 -g
endif

# ARCH: the packet tracer's SIMD width follows the target (4 lanes with
# SSE2, 8 with AVX, 16 with AVX-512). `make ARCH=` builds for baseline
# x86-64. Images are bit-identical either way (exact selects, no FMA contraction).
ARCH     ?= $(shell $(CC) -march=native -E -x c /dev/null >/dev/null 2>&1 && echo -march=native)
WARN     := -Wall -Wextra -Werror -Wshadow -Wno-unused-parameter -Wno-psabi
# No superword (SLP) vectorizing: Debian 12's GCC 12.2 vectorizes two floats
# narrowed from doubles and widened back into the original doubles, their
# rounding dropped (tests/test_compiler.c; the stress suite's double
# reference took an unrounded ray origin). It costs nothing measured
# (docs/NUMERICS.md, "The compiler"). Wherever the compiler knows the flag.
NOSLP    := $(shell $(CC) -fno-tree-slp-vectorize -E -x c /dev/null >/dev/null 2>&1 && echo -fno-tree-slp-vectorize)
NOSLPXX  := $(shell $(CXX) -fno-tree-slp-vectorize -E -x c++ /dev/null >/dev/null 2>&1 && echo -fno-tree-slp-vectorize)
# Our flags first; the user's CFLAGS/CXXFLAGS (make CFLAGS=...) add to them.
XCFLAGS  := -std=c11 -D_POSIX_C_SOURCE=200809L -D_DEFAULT_SOURCE $(OPT) $(ARCH) -ffp-contract=off \
            $(NOSLP) $(WARN) $(SANFLAGS) -MMD -MP -I. $(CFLAGS)
XCXXFLAGS := -std=c++17 $(OPT) $(ARCH) -ffp-contract=off $(NOSLPXX) -Wall -Wextra -Werror $(SANFLAGS) \
            -MMD -MP -I. $(CXXFLAGS)
LDLIBS   := -pthread -lm -ldl

# Dependency check runs once per build dir; pkg-config must exist to ask.
DEPSTAMP := $(B)/.deps-ok
$(DEPSTAMP):
	@mkdir -p $(B)
	@if command -v pkg-config >/dev/null 2>&1 && pkg-config --exists $(PKGS) $(IMGPKGS) $(TESTPKGS) \
	    && command -v gnuplot >/dev/null 2>&1 && command -v parallel >/dev/null 2>&1 \
	    && command -v rsync >/dev/null 2>&1 \
	    && command -v python3 >/dev/null 2>&1; then :; else \
	  echo "make: some dependencies are missing; running scripts/install-deps.sh"; \
	  sh scripts/install-deps.sh || { echo "make: error: could not install dependencies (see above)" >&2; exit 1; }; \
	fi
	@touch $@

# Objects depend on the flags they were built with: a changed ARCH, OPT or
# CFLAGS rebuilds everything instead of mixing stale objects in.
FLAGSTAMP := $(B)/.flags
FLAGS_NOW := $(XCFLAGS) | $(XCXXFLAGS)
$(shell mkdir -p $(B); [ "$$(cat $(FLAGSTAMP) 2>/dev/null)" = "$(FLAGS_NOW)" ] || echo "$(FLAGS_NOW)" > $(FLAGSTAMP))

PKG_CFLAGS = $(shell pkg-config --cflags $(PKGS) 2>/dev/null)
PKG_LIBS   = $(shell pkg-config --libs $(PKGS) 2>/dev/null)
IMG_CFLAGS = $(shell pkg-config --cflags $(IMGPKGS) 2>/dev/null)
IMG_LIBS   = $(shell pkg-config --libs $(IMGPKGS) 2>/dev/null)
TEST_LIBS  = $(shell pkg-config --libs $(TESTPKGS) 2>/dev/null)

MAINS    := kernel-ref/rtref.c kernel-ref/stress_main.c sim/main.c traces/replay.c
LIB_C    := $(filter-out $(MAINS),$(wildcard kernel-ref/*.c sim/*.c sim/core/*.c sim/modes/*.c units/*.c mem/*.c traces/*.c))
LIB_OBJ  := $(LIB_C:%.c=$(B)/%.o)
PLUGIN   := $(B)/libsaar-oiio.so
TEST_C   := $(wildcard tests/*.c)
TEST_OBJ := $(TEST_C:%.c=$(B)/%.o)
PROGS    := $(B)/rtref $(B)/saarsim-stress $(if $(wildcard sim/main.c),$(B)/saarsim) $(if $(wildcard traces/replay.c),$(B)/saarsim-replay)

.PHONY: all run test readme-check figures-check extend-check bench bench-fidelity bench-profile bench-scale bench-sampled bench-ratio bench-footprint bench-offsets bench-frontier stress validate calibrate drt dynamic accel mutate install clean deps
all: $(PROGS) $(PLUGIN)

deps: $(DEPSTAMP)

$(B)/%.o: %.c $(FLAGSTAMP) | $(DEPSTAMP)
	@mkdir -p $(dir $@)
	$(CC) $(XCFLAGS) $(PKG_CFLAGS) -c $< -o $@

$(B)/%.o: %.cpp $(FLAGSTAMP) | $(DEPSTAMP)
	@mkdir -p $(dir $@)
	$(CXX) $(XCXXFLAGS) -fPIC $(IMG_CFLAGS) -c $< -o $@

$(PLUGIN): $(B)/kernel-ref/image_oiio.o
	$(CXX) $(SANFLAGS) -shared -o $@ $^ $(IMG_LIBS)

$(B)/libsaar.a: $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

$(B)/rtref: $(B)/kernel-ref/rtref.o $(B)/libsaar.a
	$(CC) $(SANFLAGS) -o $@ $^ $(PKG_LIBS) $(LDLIBS)
$(B)/saarsim-stress: $(B)/kernel-ref/stress_main.o $(B)/libsaar.a
	$(CC) $(SANFLAGS) -o $@ $^ $(PKG_LIBS) $(LDLIBS)
$(B)/saarsim: $(B)/sim/main.o $(B)/libsaar.a
	$(CC) $(SANFLAGS) -o $@ $^ $(PKG_LIBS) $(LDLIBS)
$(B)/saarsim-replay: $(B)/traces/replay.o $(B)/libsaar.a
	$(CC) $(SANFLAGS) -o $@ $^ $(PKG_LIBS) $(LDLIBS)
$(B)/saarsim-tests: $(TEST_OBJ) $(B)/libsaar.a
	$(CC) $(SANFLAGS) -o $@ $^ $(PKG_LIBS) $(TEST_LIBS) $(LDLIBS)

# The main job: the embedded default scene and config, report on stdout,
# frame written to out/frame.png (saarsim once the chip model is built,
# else the reference tracer).
ifneq ($(wildcard sim/main.c),)
RUN_CMD := ./$(B)/saarsim --out out/frame.png --report out/report.json
else
RUN_CMD := ./$(B)/rtref --out out/frame.png --stats out/stats.json
endif
run: all
	@mkdir -p out
	$(RUN_CMD)

# Tests find the binaries and the shared scenes through the environment.
# The layering check (scripts/layers.py, docs/design-layers.md) runs first:
# a forbidden include or an include circle fails `make test` at once.
test: all $(B)/saarsim-tests $(PLUGIN)
	python3 scripts/layers.py
	LSAN_OPTIONS=suppressions=$(CURDIR)/tests/lsan.supp:print_suppressions=0 \
	SAAR_BIN=$(CURDIR)/$(B) SAAR_SCENES=$(or $(SAAR_SCENES),$(CURDIR)/../shared/scenes) \
	  ./$(B)/saarsim-tests --jobs 2

bench: all
	CC="$(CC)" sh scripts/bench.sh $(B)

# Run time against error of the fidelity modes; writes docs/FIDELITY.md.
bench-fidelity: all
	sh scripts/bench-fidelity.sh $(B)

# README.md's examples run in a scratch folder, their output compared with
# the page's (scripts/readme-check.py; `make test` runs it too).
readme-check: all
	SAAR_SCENES=$(or $(SAAR_SCENES),$(CURDIR)/../shared/scenes) python3 scripts/readme-check.py --bin $(B)

# The generated documents' figures rerun: the runs their generators name in
# figures-check lines (scripts/figures-check.py; `make test` runs it too).
figures-check: all
	SAAR_SCENES=$(or $(SAAR_SCENES),$(CURDIR)/../shared/scenes) python3 scripts/figures-check.py --bin $(B)

# issue 36: the profile builds its own valgrind-runnable copy (ARCH=-mavx2)
bench-profile:
	sh scripts/bench-profile.sh $(PROFILE_REVS)

bench-scale: all
	B=$(B) sh scripts/bench-scale.sh

bench-sampled: all
	B=$(B) sh scripts/bench-sampled.sh

bench-ratio: all
	B=$(B) sh scripts/bench-ratio.sh

bench-footprint: all
	B=$(B) sh scripts/bench-footprint.sh

# issue 36 target 3: sampled mode's fps error by offset on every view
# (BASE=DIR: a build of another commit for a "before" column).
bench-offsets: all
	B=$(B) sh scripts/bench-offsets.sh
bench-frontier: all
	B=$(B) sh scripts/bench-frontier.sh

# Validation against the published SaarCOR results, like with like (seed 002
# §4, Table 5; fit and held-out rows); writes docs/VALIDATION.md,
# docs/validation-published.png and docs/validation-threads.png (VALIDATE_SIZE,
# default 1024x768, VALIDATE_VIEWS: scripts/validate.sh; minutes on 2 cores).
validate: all
	sh scripts/validate.sh $(B)

# Seed 000 §5's distribution ray tracing experiments on the chip (issue 32):
# writes docs/DRT.md and docs/drt-*.png from runs in out/drt (DRT_SIZE,
# default 128x96; a few minutes on 2 cores: scripts/drt.sh).
drt: all
	sh scripts/drt.sh $(B)

# writes docs/DYNAMIC.md and docs/dynamic-fps.png from BART Robots animated
# flat and two-level (DYN_SIZE, DYN_FRAMES, DYN_FPS, DYN_T0; about a minute
# on 2 cores: scripts/dynamic.sh).
dynamic: all
	sh scripts/dynamic.sh $(B)

# The acceleration structures compared (issue 34): kd-tree, uniform grid
# and two-level trees, kernel-ref and chip, on the shared views and BART
# Robots frames; writes docs/ACCEL.md (scripts/accel.sh; a few minutes).
accel: all
	sh scripts/accel.sh $(B)

# Calibration of the assumed parameters against seed 002's figures (issue 31):
# coordinate search on Conference, writes docs/CALIBRATION.md; about 30 min
# on two cores (docs/calibration.md; CALIBRATE_ARGS: scripts/calibrate.sh).
calibrate: all
	SAARSIM=$(CURDIR)/$(B)/saarsim sh scripts/calibrate.sh $(CALIBRATE_ARGS)

# The numerical stress suite at full size; writes docs/NUMERICS.md.
stress: all
	./$(B)/saarsim-stress --out docs/NUMERICS.md
	sh scripts/precision-chip.sh $(B)

# ---- fuzzing (docs/TESTING.md) ----
# libFuzzer harnesses (clang) for the config, views, OBJ, PLY, AFF and
# memory trace readers: `make fuzz` builds them into build-fuzz/, `make
# fuzz-smoke` runs each for FUZZ_SECONDS (default 20) from the seeds in
# tests/fuzz/seeds/ and files the repository and shared scenes already
# have; FUZZ_SECONDS=600 is the long run. A finding stops the run with the
# input saved as build-fuzz/<harness>-crash-*.
FZ_B      := build-fuzz
FZ_CC     ?= clang
FZ_CXX    ?= clang++
FZ_SAN    := -fsanitize=address,undefined -fno-sanitize-recover=undefined
FZ_CFLAGS := -std=c11 -D_POSIX_C_SOURCE=200809L -D_DEFAULT_SOURCE -O1 -g -ffp-contract=off \
             -Wall -Wextra -Werror -Wshadow -Wno-unused-parameter $(FZ_SAN) \
             -I. -Itests/fuzz
FZ_OBJ    := $(LIB_C:%.c=$(FZ_B)/%.o)
FZ_NAMES  := config views trace obj ply aff
FZ_BINS   := $(FZ_NAMES:%=$(FZ_B)/fuzz-%)
FUZZ_SECONDS ?= 20

.PHONY: fuzz fuzz-smoke fuzz-syntax
fuzz: $(FZ_BINS)

# What `make fuzz` compiles, checked by its compiler and flags without
# building anything (tests/test_runner.c runs it in `make test`): clang
# refuses under -Werror what gcc lets pass (a struct initialiser short of
# a field broke `make fuzz` unseen). Without clang there is nothing to
# check: it says so and succeeds.
fuzz-syntax:
	@command -v $(FZ_CC) >/dev/null 2>&1 || { echo "fuzz-syntax: $(FZ_CC) not found, nothing checked"; exit 0; }; \
	for f in $(LIB_C) $(wildcard tests/fuzz/fuzz_*.c); do \
	  $(FZ_CC) $(FZ_CFLAGS) $(PKG_CFLAGS) -DFUZZ_EXT='".obj"' -fsyntax-only $$f || exit 1; \
	done

$(FZ_B)/%.o: %.c | $(DEPSTAMP)
	@mkdir -p $(dir $@)
	$(FZ_CC) $(FZ_CFLAGS) -fsanitize=fuzzer-no-link $(PKG_CFLAGS) -c $< -o $@
$(FZ_B)/libsaar-fuzz.a: $(FZ_OBJ)
	@rm -f $@
	ar rcs $@ $^
$(FZ_B)/fuzz-obj: tests/fuzz/fuzz_scene.c tests/fuzz/fuzz.h $(FZ_B)/libsaar-fuzz.a
	$(FZ_CXX) -x c $(FZ_CFLAGS) -DFUZZ_EXT='".obj"' -fsanitize=fuzzer $< -x none $(FZ_B)/libsaar-fuzz.a $(PKG_LIBS) $(LDLIBS) -o $@
$(FZ_B)/fuzz-ply: tests/fuzz/fuzz_scene.c tests/fuzz/fuzz.h $(FZ_B)/libsaar-fuzz.a
	$(FZ_CXX) -x c $(FZ_CFLAGS) -DFUZZ_EXT='".ply"' -fsanitize=fuzzer $< -x none $(FZ_B)/libsaar-fuzz.a $(PKG_LIBS) $(LDLIBS) -o $@
$(FZ_B)/fuzz-%: tests/fuzz/fuzz_%.c tests/fuzz/fuzz.h $(FZ_B)/libsaar-fuzz.a
	$(FZ_CXX) -x c $(FZ_CFLAGS) -fsanitize=fuzzer $< -x none $(FZ_B)/libsaar-fuzz.a $(PKG_LIBS) $(LDLIBS) -o $@

fuzz-smoke: fuzz all
	sh scripts/fuzz-run.sh $(FZ_B) $(FUZZ_SECONDS) $(B) $(FZ_NAMES)
# Standing mutation tests in a scratch copy (build-mutate/); writes the
# table in docs/TESTING.md and fails unless every mutant is caught by the
# tests it names (scripts/mutate.sh). Not part of `make test`.
mutate:
	sh scripts/mutate.sh

# docs/extending.md's unit-kind walk-through (tests/extend/unit-clip.patch)
# applied to a scratch copy (build-extend/), built and run; `make test`
# checks only that the page and the patch show the same lines.
extend-check:
	sh scripts/extend-check.sh

install: all
	install -d $(DESTDIR)$(PREFIX)/bin
	install -m 755 $(PROGS) $(DESTDIR)$(PREFIX)/bin/
	install -d $(DESTDIR)$(PREFIX)/lib/saarsim
	install -m 644 $(PLUGIN) $(DESTDIR)$(PREFIX)/lib/saarsim/

clean:
	rm -rf build build-san build-fuzz build-mutate build-extend

-include $(LIB_OBJ:.o=.d) $(TEST_OBJ:.o=.d) $(MAINS:%.c=$(B)/%.d)
