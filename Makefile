# bspray — plain Makefile. gcc by default; `make CC=clang` must build warning-free too.
#
#   make            libraries (build/public/libbspray.a and build/libbspray.so for users,
#                   build/libbspray.a with the internal names for the CLI and tests), CLI
#   make run        render the built-in default scene, write out/balls.png, print statistics
#   make test       build and run every test (ends with "N passed, N failed")
#   make asan-test  the same suite under AddressSanitizer + UndefinedBehaviorSanitizer
#                   (fewer random rays: BSPRAY_TEST_QUICK=1)
#   make embree-compare  build/bspray-embree: primary-ray throughput against Intel Embree 3
#                   on the same rays (needs libembree-dev; docs/embree.md). Not part of `all`.
#   make tsan-test  the tests that run threads under ThreadSanitizer (needs clang)
#   make fuzz       build-fuzz/fuzz_*: libFuzzer targets (needs clang; fuzz/run.sh runs them)
#   make install    PREFIX=/usr/local (and DESTDIR for staging): both libraries, the
#                   headers, the CLI and a pkg-config file (bspray.pc)
#   make clean

CC      ?= gcc
BUILD   ?= build
OPT     ?= -O2 -g
SAN     ?=
WARN    := -Wall -Wextra -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Werror
CFLAGS  ?=
# -ffp-contract=off: no multiply-add is fused, so that a kernel's t has the
# same bits wherever it is inlined (and in naive_blocks.c's vector copies of
# the kernels' first tests) even where CFLAGS enables FMA (-march=native)
ALL_CFLAGS := -std=c11 -D_POSIX_C_SOURCE=200809L $(WARN) $(OPT) $(SAN) -ffp-contract=off \
              -pthread -Iinclude -Isrc -MMD -MP $(CFLAGS)
LDLIBS  := -lpng -lz -lm -pthread
LDFLAGS ?=

LIB_SRC  := $(sort $(wildcard src/*/*.c))
TEST_SRC := $(sort $(wildcard tests/*.c))
# PIC_ONLY=1 (the sanitizer suite) makes the static library of the
# position-independent objects the shared one is made of, so that the
# library is compiled once rather than twice
LIB_OBJ  := $(if $(PIC_ONLY),$(LIB_SRC:%.c=$(BUILD)/pic/%.o),$(LIB_SRC:%.c=$(BUILD)/obj/%.o))
TEST_OBJ := $(TEST_SRC:%.c=$(BUILD)/obj/%.o)
CLI_OBJ  := $(patsubst %.c,$(BUILD)/obj/%.o,$(sort $(wildcard tools/*.c)))
# tools/embree/ is outside that wildcard: only `make embree-compare` needs Embree
EMBREE_OBJ := $(BUILD)/obj/tools/embree/compare.o

# examples/ uses the public headers alone (no -Isrc): what an installed library offers
EXAMPLE_SRC := $(sort $(wildcard examples/*.c))
EXAMPLES    := $(EXAMPLE_SRC:examples/%.c=$(BUILD)/examples/%)
# the same programs linked to the shared library (found beside them by rpath)
EXAMPLES_SHARED := $(EXAMPLE_SRC:examples/%.c=$(BUILD)/examples/%-shared)
# examples/*.cpp: the API from C++ (the public headers are extern "C"), built
# with $(CXX) against the public static library
EXAMPLE_CXX_SRC := $(sort $(wildcard examples/*.cpp))
EXAMPLES        += $(EXAMPLE_CXX_SRC:examples/%.cpp=$(BUILD)/examples/%)
CXX      ?= g++
WARN_CXX := -Wall -Wextra -Wshadow -Wpedantic -Werror

LIB   := $(BUILD)/libbspray.a
# The shared library: position-independent copies of the library's objects,
# exporting only the public API (the bsp_* functions of include/bspray/,
# src/libbspray.map). While the version is 0.x the ABI may change with the
# minor version, so the soname carries both: libbspray.so.0.2.
VERSION := $(shell sed -n 's/^\#define BSPRAY_VERSION_STRING "\(.*\)"/\1/p' include/bspray/bspray.h)
SONAME  := libbspray.so.$(basename $(VERSION))
SHLIB   := $(BUILD)/libbspray.so.$(VERSION)
PIC_OBJ := $(LIB_SRC:%.c=$(BUILD)/pic/%.o)
# The static library users get (make install, examples/): the library's objects
# linked into one, every symbol but the public API's made local, so that a
# program with a function named like an internal one (error_set, draw_line, ...)
# still links. The CLI and the tests link $(LIB), which keeps the internal names.
PUBLIC_LIB := $(BUILD)/public/libbspray.a
OBJCOPY ?= objcopy
CLI   := $(BUILD)/bspray
TESTS := $(BUILD)/bspray_tests
EMBREE_CLI := $(BUILD)/bspray-embree

.PHONY: all run test asan-test tsan-test clean embree-compare examples install shared fuzz
all: $(LIB) $(PUBLIC_LIB) $(BUILD)/libbspray.so $(CLI) $(TESTS) $(EXAMPLES) $(EXAMPLES_SHARED)
examples: $(EXAMPLES) $(EXAMPLES_SHARED)
shared: $(BUILD)/libbspray.so

$(BUILD)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -c $< -o $@

$(BUILD)/pic/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -fPIC -c $< -o $@

$(SHLIB): $(PIC_OBJ) src/libbspray.map
	$(CC) $(ALL_CFLAGS) $(LDFLAGS) -shared -Wl,-soname,$(SONAME) \
	    -Wl,--version-script=src/libbspray.map -o $@ $(PIC_OBJ) $(LDLIBS)

$(BUILD)/$(SONAME) $(BUILD)/libbspray.so: $(SHLIB)
	ln -sf $(notdir $(SHLIB)) $@

$(BUILD)/public/libbspray.o: $(LIB_OBJ)
	@mkdir -p $(dir $@)
	$(CC) -r -nostdlib -o $@.all $(LIB_OBJ)
	$(OBJCOPY) --wildcard --keep-global-symbol='bsp_*' $@.all $@
	rm -f $@.all

$(PUBLIC_LIB): $(BUILD)/public/libbspray.o
	rm -f $@
	ar rcs $@ $<

$(LIB): $(LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@
	ar rcs $@ $^

$(CLI): $(CLI_OBJ) $(LIB)
	$(CC) $(ALL_CFLAGS) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(TESTS): $(TEST_OBJ) $(LIB)
	$(CC) $(ALL_CFLAGS) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(BUILD)/examples/%: examples/%.c $(PUBLIC_LIB)
	@mkdir -p $(dir $@)
	$(CC) -std=c11 $(WARN) $(OPT) $(SAN) -pthread -Iinclude $(CFLAGS) $(LDFLAGS) -o $@ $< $(PUBLIC_LIB) $(LDLIBS)

$(BUILD)/examples/%: examples/%.cpp $(PUBLIC_LIB)
	@mkdir -p $(dir $@)
	$(CXX) -std=c++11 $(WARN_CXX) $(OPT) $(SAN) -pthread -Iinclude $(CXXFLAGS) $(LDFLAGS) -o $@ $< $(PUBLIC_LIB) $(LDLIBS)

# A program that defines functions and data named like the library's internal
# ones, linked to the public static library: it links only if they are hidden.
$(BUILD)/tests/names_apart: tests/link/names_apart.c $(PUBLIC_LIB)
	@mkdir -p $(dir $@)
	$(CC) -std=c11 $(WARN) $(OPT) $(SAN) -pthread -Iinclude $(CFLAGS) $(LDFLAGS) -o $@ $< $(PUBLIC_LIB) $(LDLIBS)

# Every allocation of the library made to fail in turn (tests/oom/oom_sweep.c):
# its calls to malloc, calloc, realloc and free reach the program's wrappers.
OOM_WRAP := -Wl,--wrap=malloc,--wrap=calloc,--wrap=realloc,--wrap=free
$(BUILD)/tests/oom_sweep: tests/oom/oom_sweep.c $(LIB)
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) $(LDFLAGS) $(OOM_WRAP) -o $@ $< $(LIB) $(LDLIBS)

$(BUILD)/examples/%-shared: examples/%.c $(BUILD)/libbspray.so $(BUILD)/$(SONAME)
	@mkdir -p $(dir $@)
	$(CC) -std=c11 $(WARN) $(OPT) $(SAN) -pthread -Iinclude $(CFLAGS) $(LDFLAGS) -o $@ $< \
	    -L$(BUILD) -Wl,-rpath,'$$ORIGIN/..' -lbspray -lm

embree-compare: $(EMBREE_CLI)

$(EMBREE_CLI): $(EMBREE_OBJ) $(LIB)
	$(CC) $(ALL_CFLAGS) $(LDFLAGS) -o $@ $^ -lembree3 $(LDLIBS)

# The default scene: SPD balls (sphereflake), 513x513 rays (SPD protocol), depth 4.
run: $(CLI)
	@mkdir -p out
	./$(CLI) render $(DEFAULT_SCENE) -o out/balls.png

DEFAULT_SCENE ?= spd:balls

test: $(CLI) $(TESTS) $(EXAMPLES) $(EXAMPLES_SHARED) $(BUILD)/tests/names_apart $(BUILD)/tests/oom_sweep
	BSPRAY_CLI=./$(CLI) ./$(TESTS)

# The sanitizer run checks the same things with fewer random rays and the
# every-ray render checks at 65 x 65 instead of 513 x 513 (BSPRAY_TEST_QUICK),
# at -O2 (the checks are the same; it ran about a fifth faster than at -O1),
# with -g1: the line tables a report's stack needs, not the variables' (a
# fifth less compile time).
asan-test:
	BSPRAY_TEST_QUICK=1 $(MAKE) BUILD=build-asan PIC_ONLY=1 OPT="-O2 -g1 -fno-omit-frame-pointer" \
	    SAN="-fsanitize=address,undefined -fno-sanitize-recover=all" test

# The tests that run threads, under ThreadSanitizer (needs clang): ray
# batches, renders on one and two threads, the parallel SAH build (1 and 3
# threads, byte for byte; and with the leaf budget's estimate, whose scouts,
# probes and other tasks the threads take in turn), the first calls of bsp_spd_scene_names from four
# threads, scenes loaded and structures built and queried on four threads at
# once, and the allocation sweep's two-thread scenarios.
# A race report exits the program with status 66, which fails the test.
TSAN_BUILD := build-tsan
TSAN_TESTS := batch_ spd_names_list threads_share render_identical render_tiles sah_build_is_deterministic sah_leaf_budget_estimate bvh_build_is_deterministic every_allocation
tsan-test:
	$(MAKE) BUILD=$(TSAN_BUILD) CC=clang CXX=clang++ OPT="-O1 -g" SAN="-fsanitize=thread" \
	    $(TSAN_BUILD)/bspray $(TSAN_BUILD)/bspray_tests $(TSAN_BUILD)/tests/oom_sweep
	for t in $(TSAN_TESTS); do \
	    BSPRAY_TEST_QUICK=1 BSPRAY_CLI=./$(TSAN_BUILD)/bspray TSAN_OPTIONS=halt_on_error=1 \
	        ./$(TSAN_BUILD)/bspray_tests $$t || exit 1; \
	done

# Fuzz targets (fuzz/, libFuzzer: needs clang): the library built again with
# the sanitizers and libFuzzer's coverage, and one program per target.
# fuzz/run.sh makes a seed corpus and runs them (docs/fuzzing.md).
FUZZ_BUILD   := build-fuzz
FUZZ_SAN     := -fsanitize=address,undefined -fno-sanitize-recover=all
FUZZ_TARGETS := $(patsubst fuzz/%.c,$(FUZZ_BUILD)/%,$(sort $(wildcard fuzz/fuzz_*.c)))

fuzz:
	$(MAKE) BUILD=$(FUZZ_BUILD) CC=clang OPT="-O1 -g" SAN="$(FUZZ_SAN) -fsanitize=fuzzer-no-link" \
	    $(FUZZ_BUILD)/libbspray.a
	$(MAKE) CC=clang $(FUZZ_TARGETS)

$(FUZZ_BUILD)/fuzz_%: fuzz/fuzz_%.c fuzz/fuzz_input.h $(FUZZ_BUILD)/libbspray.a
	clang -std=c11 -D_POSIX_C_SOURCE=200809L $(WARN) -O1 -g -ffp-contract=off $(FUZZ_SAN) -fsanitize=fuzzer \
	    -Iinclude -Isrc -o $@ $< $(FUZZ_BUILD)/libbspray.a $(LDLIBS)

PREFIX  ?= /usr/local
DESTDIR ?=

# Both libraries: `pkg-config --libs bspray` links the shared one (its own
# dependencies are recorded in it), `pkg-config --static --libs bspray` adds
# Libs.private for the static one.
install: $(PUBLIC_LIB) $(SHLIB) $(CLI)
	install -d $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/include/bspray \
	    $(DESTDIR)$(PREFIX)/bin
	install -m 644 $(PUBLIC_LIB) $(DESTDIR)$(PREFIX)/lib/
	install -m 755 $(SHLIB) $(DESTDIR)$(PREFIX)/lib/
	ln -sf $(notdir $(SHLIB)) $(DESTDIR)$(PREFIX)/lib/$(SONAME)
	ln -sf $(SONAME) $(DESTDIR)$(PREFIX)/lib/libbspray.so
	install -m 644 include/bspray/*.h $(DESTDIR)$(PREFIX)/include/bspray/
	install -m 755 $(CLI) $(DESTDIR)$(PREFIX)/bin/
	printf '%s\n' 'prefix=$(PREFIX)' 'libdir=$${prefix}/lib' 'includedir=$${prefix}/include' '' \
	    'Name: bspray' \
	    'Description: exact ray shooting with adaptive BSP trees (kd-trees)' \
	    'Version: $(VERSION)' \
	    'Cflags: -I$${includedir}' \
	    'Libs: -L$${libdir} -lbspray' \
	    'Libs.private: -lpng -lz -lm -pthread' \
	    > $(DESTDIR)$(PREFIX)/lib/pkgconfig/bspray.pc

clean:
	rm -rf build build-asan build-clang $(FUZZ_BUILD) out

-include $(PIC_OBJ:.o=.d) $(LIB_OBJ:.o=.d) $(TEST_OBJ:.o=.d) $(CLI_OBJ:.o=.d) $(EMBREE_OBJ:.o=.d)
