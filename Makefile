# libdem / pydem — one entry point.
#   make            static + shared library (strict warnings, warnings are errors); no Python needed
#   make pydem      the Python binding in place (pydem/_libdem*.so; the set-up makes .venv)
#   make test       set-up (idempotent), build, every C test (plain, then under ASan/UBSan),
#                   then the Python tests; prints the slowest tests and each stage's time
#   make test-quick the edit-test loop (a few minutes): the C tests once, the Python tests not marked slow
#   make bench      benchmarks (results in bench/results/)
#   make demo       the main job (calibration of glass microbeads, report in build/calibration;
#                   the diagnosis loop, reports in build/diagnosis)
#   make install PREFIX=/usr/local   libdem for any x86-64 (headers, libdem.a, libdem.so.MAJOR, dem.pc)
CC      ?= gcc
PREFIX  ?= /usr/local
BUILD   := build
# AVX2 encoding when both the compiler and this machine support it: measured ~15 % faster on
# the benchmark machine; results are unchanged (no FMA contraction under -std=c99). Set
# ARCH_OPT= to build for any x86-64, e.g. for a library shipped to other machines.
ARCH_OPT ?= $(shell grep -qw avx2 /proc/cpuinfo 2>/dev/null && $(CC) -march=x86-64-v3 -x c -c /dev/null -o /dev/null 2>/dev/null && echo -march=x86-64-v3)
OPT     ?= -O3 -fno-math-errno -fno-trapping-math $(ARCH_OPT)
# The screening kernel (mlp_screen.c) is one long vector loop: AVX-512 when this machine has it
# (ARCH_OPT_WIDE= to turn off; it follows ARCH_OPT otherwise).
ARCH_OPT_WIDE ?= $(if $(ARCH_OPT),$(shell grep -qw avx512f /proc/cpuinfo 2>/dev/null && $(CC) -march=x86-64-v4 -x c -c /dev/null -o /dev/null 2>/dev/null && echo -march=x86-64-v4 -mprefer-vector-width=512))
# HDF5 (snapshots) and libpng (images), installed by scripts/setup.sh. HDF5=0 / PNG=0 build
# without them (for embedding): those calls then return DEM_ERR_UNSUPPORTED.
HDF5 ?= 1
PNG  ?= 1
DEP_PKGS    := $(if $(filter 1,$(HDF5)),hdf5-serial) $(if $(filter 1,$(PNG)),libpng)
DEP_FALLBACK := $(if $(filter 1,$(HDF5)),-lhdf5) $(if $(filter 1,$(PNG)),-lpng)
DEPS_CFLAGS := $(if $(strip $(DEP_PKGS)),$(shell pkg-config --cflags $(DEP_PKGS) 2>/dev/null)) \
               $(if $(filter 0,$(HDF5)),-DDEM_NO_HDF5) $(if $(filter 0,$(PNG)),-DDEM_NO_PNG)
DEPS_LIBS   := $(if $(strip $(DEP_PKGS)),$(shell pkg-config --libs $(DEP_PKGS) 2>/dev/null || echo $(DEP_FALLBACK)))
CFLAGS  += -std=c99 -Wall -Wextra -Wpedantic -Werror -fPIC -fopenmp -fvisibility=hidden $(OPT) -Iinclude -Ilibdem $(DEPS_CFLAGS)
LDLIBS  += $(DEPS_LIBS) -lm
PYTHON  := .venv/bin/python

LIB_SRC := $(wildcard libdem/*.c)
LIB_OBJ := $(patsubst libdem/%.c,$(BUILD)/obj/%.o,$(LIB_SRC))
HEADERS := $(wildcard include/dem/*.h) $(wildcard libdem/*.h)
TEST_SRC := $(wildcard tests/c/test_*.c)
TEST_BIN := $(patsubst tests/c/%.c,$(BUILD)/tests/%,$(TEST_SRC))
BENCH_SRC := $(wildcard bench/*.c)
BENCH_BIN := $(patsubst bench/%.c,$(BUILD)/bench/%,$(BENCH_SRC))

.PHONY: all lib pydem setup test test-quick test-c test-sanitize test-minimal test-py bench bench-screening demo install clean FORCE

all: lib
lib: $(BUILD)/libdem.a $(BUILD)/libdem.so $(BUILD)/dem.pc

VERSION := $(shell sed -n 's/\#define DEM_VERSION_STRING "\(.*\)"/\1/p' include/dem/base.h)
SONAME  := libdem.so.$(firstword $(subst ., ,$(VERSION)))

$(BUILD)/obj/%.o: libdem/%.c $(HEADERS)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -DDEM_BUILD_SHARED -c $< -o $@

$(BUILD)/obj/mlp_screen.o: CFLAGS += $(ARCH_OPT_WIDE)

$(BUILD)/libdem.a: $(LIB_OBJ)
	@rm -f $@
	ar rcs $@ $^

# versioned soname, no rpath: an installed libdem.so.0 is found by the loader's own rules
$(BUILD)/libdem.so: $(LIB_OBJ)
	$(CC) -shared -fopenmp -Wl,-soname,$(SONAME) -o $@ $^ $(LDLIBS)

# pkg-config file for PREFIX (rewritten whenever PREFIX differs from the last one)
$(BUILD)/dem.pc: FORCE
	@mkdir -p $(BUILD)
	@printf 'prefix=%s\nlibdir=$${prefix}/lib\nincludedir=$${prefix}/include\n\nName: dem\nDescription: libdem discrete element method library\nVersion: %s\nLibs: -L$${libdir} -ldem -fopenmp -lm\nRequires.private: hdf5-serial libpng\nCflags: -I$${includedir}\n' \
	  "$(PREFIX)" "$(VERSION)" > $@.tmp
	@cmp -s $@.tmp $@ || mv $@.tmp $@; rm -f $@.tmp

setup:
	@sh scripts/setup.sh

# every malloc/calloc/realloc of the static library counted (tests/c/test_no_alloc.c)
$(BUILD)/tests/test_no_alloc: LDLIBS += -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc

$(BUILD)/tests/%: tests/c/%.c $(wildcard tests/c/*.h) $(BUILD)/libdem.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $< -o $@ $(BUILD)/libdem.a -lcmocka $(LDLIBS)

# each stage timed; the total goes into the CHANGELOG at each release. The C tests first (a broken
# library fails fast); then the sanitizer and minimal builds run beside the Python tests, filling the
# cores that each leaves idle (a long last test, a long sanitized program); their log is printed after
test: setup
	@t0=$$(date +%s); $(MAKE) -j$(shell nproc) --no-print-directory test-c || exit 1; \
	echo "== test-c: $$(( $$(date +%s) - t0 )) s"; s=$$(date +%s); mkdir -p $(BUILD); rm -f $(BUILD)/test-native.rc; \
	( $(MAKE) --no-print-directory test-sanitize test-minimal > $(BUILD)/test-native.log 2>&1; \
	  echo $$? > $(BUILD)/test-native.rc; echo "== test-sanitize, test-minimal: $$(( $$(date +%s) - s )) s" >> $(BUILD)/test-native.log ) & \
	$(MAKE) --no-print-directory test-py; py=$$?; echo "== test-py: $$(( $$(date +%s) - s )) s"; wait; \
	cat $(BUILD)/test-native.log; [ "$$(cat $(BUILD)/test-native.rc 2>/dev/null)" = 0 ] || { echo "FAILED: test-sanitize or test-minimal"; exit 1; }; \
	[ $$py = 0 ] || exit 1; echo "== make test passed in $$(( $$(date +%s) - t0 )) s"

# the edit-test loop: the C tests once (no sanitizers), the Python tests not marked slow
test-quick: setup
	@t0=$$(date +%s); $(MAKE) --no-print-directory test-c && \
	  $(MAKE) --no-print-directory PYTEST_ARGS='-m "not slow"' test-py && \
	  echo "== make test-quick passed in $$(( $$(date +%s) - t0 )) s"

# libdem without HDF5 and libpng (HDF5=0 PNG=0), linked without them
test-minimal:
	@echo "== libdem built and linked without HDF5 and libpng"
	@$(MAKE) --no-print-directory -s BUILD=$(BUILD)/minimal HDF5=0 PNG=0 OPT=-O1 $(BUILD)/minimal/libdem.a
	@$(CC) -std=c99 -Wall -Wextra -Werror -fopenmp -Iinclude tests/c/minimal/test_minimal_build.c -o $(BUILD)/minimal/test_minimal_build \
	  $(BUILD)/minimal/libdem.a -lcmocka -lm
	@cd $(BUILD)/minimal && ./test_minimal_build

# every C test again under AddressSanitizer + UndefinedBehaviorSanitizer (+ leak check), with the
# library's internal invariants checked (DEM_CHECKS)
SAN_OPT := -O1 -g -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=all -DDEM_CHECKS
test-sanitize:
	@echo "== C tests under ASan + UBSan"
	@mkdir -p $(BUILD)
	@$(MAKE) --no-print-directory -s -j$(shell nproc) BUILD=$(BUILD)/sanitize OPT="$(SAN_OPT)" lib $(TEST_BIN:$(BUILD)/%=$(BUILD)/sanitize/%) > $(BUILD)/sanitize.log 2>&1 \
	  || (cat $(BUILD)/sanitize.log; echo "sanitizer build FAILED (log: $(BUILD)/sanitize.log)"; exit 1)
	@$(MAKE) --no-print-directory -s BUILD=$(BUILD)/sanitize OPT="$(SAN_OPT)" test-c >> $(BUILD)/sanitize.log 2>&1 \
	  || (cat $(BUILD)/sanitize.log; echo "sanitizer run FAILED (log: $(BUILD)/sanitize.log)"; exit 1)
	@grep -cE "^\[  PASSED  \]" $(BUILD)/sanitize.log | xargs printf "   %s test programs passed (log: $(BUILD)/sanitize.log)\n"

# the test programs one per core at a time, the longest first (most are single-threaded at their
# sizes; under the sanitizers test_stress alone runs ~80 s), each one's output printed whole, in order
LONG_TESTS := $(filter %/test_stress %/test_determinism,$(TEST_BIN))
test-c: lib $(TEST_BIN) $(BUILD)/libdem_example
	@printf '%s\n' $(LONG_TESTS) $(filter-out $(LONG_TESTS),$(TEST_BIN)) | xargs -P $(shell nproc) -I{} sh -c 'OMP_NUM_THREADS=2 {} > {}.log 2>&1; echo $$? > {}.rc'
	@fail=0; for t in $(TEST_BIN); do echo "== $$t"; cat $$t.log; [ "$$(cat $$t.rc)" = 0 ] || { echo "FAILED: $$t"; fail=1; }; \
	  done; exit $$fail
	@echo "== docs/libdem.md example"; $(BUILD)/libdem_example

$(BUILD)/libdem_example: docs/libdem.md $(BUILD)/libdem.a
	@mkdir -p $(BUILD)
	sed -n '/^```c libdem-example/,/^```/p' docs/libdem.md | sed '1d;$$d' > $(BUILD)/libdem_example.c
	$(CC) $(CFLAGS) $(BUILD)/libdem_example.c -o $@ $(BUILD)/libdem.a $(LDLIBS)

# the Python binding (cffi, API mode) over the headers and the static library
PYDEM_STAMP := $(BUILD)/pydem.stamp
pydem: $(PYDEM_STAMP)
$(PYDEM_STAMP): $(BUILD)/libdem.a $(wildcard include/dem/*.h) pydem/_build_ffi.py
	$(PYTHON) pydem/_build_ffi.py
	@rm -f pydem/_libdem.abi3.so  # the source-built copy of `pip install -e .`: one binding, make's
	@touch $@

# the 15 slowest tests are listed after every run, so a test that grows is seen; one worker per
# core (pytest-xdist), each test where a worker is free (a module fixture is made once per worker)
PYTEST_ARGS ?=
PYTEST_WORKERS ?= $(shell nproc)
test-py: pydem
	$(PYTHON) -m pytest -q --durations=15 -n $(PYTEST_WORKERS) --dist worksteal $(PYTEST_ARGS) tests/py

$(BUILD)/bench/%: bench/%.c bench/lattice.h $(BUILD)/libdem.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $< -o $@ $(BUILD)/libdem.a $(LDLIBS)

bench: setup lib $(BENCH_BIN)
	@sh bench/run_bench.sh

# the main job: calibrate glass microbeads on the shipped diagnosis stores (posterior, seed 000's
# admissible set screened natively over 2^20 combinations, nets exported; build/calibration),
# then the diagnosis loop: a synthetic material made by our rigs with a hidden effect (the loop
# must find it), and the glass microbeads (build/diagnosis)
# the synthetic material was made by the default-preset rigs: it is diagnosed with the default stores
demo: setup lib
	@$(MAKE) --no-print-directory pydem
	.venv/bin/pydem calibrate data/measurements/glass_microbeads.csv --material glass_microbeads --out $(BUILD)/calibration
	.venv/bin/pydem diagnose data/measurements/synthetic_cohesive.csv --material synthetic_cohesive \
	  --out $(BUILD)/diagnosis/synthetic_cohesive
	.venv/bin/pydem diagnose data/measurements/glass_microbeads.csv --material glass_microbeads \
	  --out $(BUILD)/diagnosis/glass_microbeads
	@# the refinement (docs/diagnosis.md §8) from its shipped runs, so the demo stays fast; without
	@# data/refine the same command runs the 16 DEM runs (~1 h on 2 cores)
	@rm -rf $(BUILD)/diagnosis/synthetic_cohesive_refined.refine && mkdir -p $(BUILD)/diagnosis && \
	  cp -r data/refine/synthetic_cohesive.refine $(BUILD)/diagnosis/synthetic_cohesive_refined.refine
	.venv/bin/pydem diagnose data/measurements/synthetic_cohesive.csv --material synthetic_cohesive \
	  --out $(BUILD)/diagnosis/synthetic_cohesive_refined --refine 16

# screening throughput: libdem vs torch on the nets `make demo` trained
bench-screening: setup lib
	@$(MAKE) --no-print-directory pydem
	@[ -d $(BUILD)/calibration/nets ] || $(MAKE) --no-print-directory demo
	$(PYTHON) bench/screening.py

# installed from a portable build (no -march: the library may run on another machine than this)
PORTABLE := $(BUILD)/portable
install:
	@$(MAKE) --no-print-directory BUILD=$(PORTABLE) ARCH_OPT= ARCH_OPT_WIDE= PREFIX=$(PREFIX) lib
	install -d $(DESTDIR)$(PREFIX)/include/dem $(DESTDIR)$(PREFIX)/lib/pkgconfig
	install -m 644 include/dem/*.h $(DESTDIR)$(PREFIX)/include/dem/
	install -m 644 $(PORTABLE)/libdem.a $(DESTDIR)$(PREFIX)/lib/
	install -m 755 $(PORTABLE)/libdem.so $(DESTDIR)$(PREFIX)/lib/libdem.so.$(VERSION)
	ln -sf libdem.so.$(VERSION) $(DESTDIR)$(PREFIX)/lib/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(PREFIX)/lib/libdem.so
	install -m 644 $(PORTABLE)/dem.pc $(DESTDIR)$(PREFIX)/lib/pkgconfig/dem.pc

clean:
	rm -rf $(BUILD)
