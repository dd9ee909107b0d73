# bspray — plain Makefile. gcc by default; `make CC=clang` must build warning-free too.
#
#   make            library (build/libbspray.a) and CLI (build/bspray)
#   make run        render the built-in default scene, write out/balls.png, print statistics
#   make test       build and run every test (ends with "N passed, N failed")
#   make asan-test  the same suite under AddressSanitizer + UndefinedBehaviorSanitizer
#                   (fewer random rays: BSPRAY_TEST_QUICK=1)
#   make embree-compare  build/bspray-embree: primary-ray throughput against Intel Embree 3
#                   on the same rays (needs libembree-dev; docs/embree.md). Not part of `all`.
#   make install    PREFIX=/usr/local (and DESTDIR for staging): the library, its headers,
#                   the CLI and a pkg-config file (bspray.pc)
#   make clean

CC      ?= gcc
BUILD   ?= build
OPT     ?= -O2 -g
SAN     ?=
WARN    := -Wall -Wextra -Wshadow -Wstrict-prototypes -Wmissing-prototypes -Werror
CFLAGS  ?=
ALL_CFLAGS := -std=c11 -D_POSIX_C_SOURCE=200809L $(WARN) $(OPT) $(SAN) -pthread \
              -Iinclude -Isrc -MMD -MP $(CFLAGS)
LDLIBS  := -lpng -lz -lm -pthread
LDFLAGS ?=

LIB_SRC  := $(sort $(wildcard src/*/*.c))
TEST_SRC := $(sort $(wildcard tests/*.c))
LIB_OBJ  := $(LIB_SRC:%.c=$(BUILD)/obj/%.o)
TEST_OBJ := $(TEST_SRC:%.c=$(BUILD)/obj/%.o)
CLI_OBJ  := $(patsubst %.c,$(BUILD)/obj/%.o,$(sort $(wildcard tools/*.c)))
# tools/embree/ is outside that wildcard: only `make embree-compare` needs Embree
EMBREE_OBJ := $(BUILD)/obj/tools/embree/compare.o

# examples/ uses the public headers alone (no -Isrc): what an installed library offers
EXAMPLE_SRC := $(sort $(wildcard examples/*.c))
EXAMPLES    := $(EXAMPLE_SRC:examples/%.c=$(BUILD)/examples/%)

LIB   := $(BUILD)/libbspray.a
CLI   := $(BUILD)/bspray
TESTS := $(BUILD)/bspray_tests
EMBREE_CLI := $(BUILD)/bspray-embree

.PHONY: all run test asan-test clean embree-compare examples install
all: $(LIB) $(CLI) $(EXAMPLES)
examples: $(EXAMPLES)

$(BUILD)/obj/%.o: %.c
	@mkdir -p $(dir $@)
	$(CC) $(ALL_CFLAGS) -c $< -o $@

$(LIB): $(LIB_OBJ)
	@mkdir -p $(dir $@)
	rm -f $@
	ar rcs $@ $^

$(CLI): $(CLI_OBJ) $(LIB)
	$(CC) $(ALL_CFLAGS) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(TESTS): $(TEST_OBJ) $(LIB)
	$(CC) $(ALL_CFLAGS) $(LDFLAGS) -o $@ $^ $(LDLIBS)

$(BUILD)/examples/%: examples/%.c $(LIB)
	@mkdir -p $(dir $@)
	$(CC) -std=c11 $(WARN) $(OPT) $(SAN) -pthread -Iinclude $(CFLAGS) $(LDFLAGS) -o $@ $< $(LIB) $(LDLIBS)

embree-compare: $(EMBREE_CLI)

$(EMBREE_CLI): $(EMBREE_OBJ) $(LIB)
	$(CC) $(ALL_CFLAGS) $(LDFLAGS) -o $@ $^ -lembree3 $(LDLIBS)

# The default scene: SPD balls (sphereflake), 513x513 rays (SPD protocol), depth 4.
run: $(CLI)
	@mkdir -p out
	./$(CLI) render $(DEFAULT_SCENE) -o out/balls.png

DEFAULT_SCENE ?= spd:balls

test: $(CLI) $(TESTS) $(EXAMPLES)
	BSPRAY_CLI=./$(CLI) ./$(TESTS)

# The sanitizer run checks the same things with fewer random rays and the
# every-ray render checks at 65 x 65 instead of 513 x 513 (BSPRAY_TEST_QUICK).
asan-test:
	BSPRAY_TEST_QUICK=1 $(MAKE) BUILD=build-asan OPT="-O1 -g -fno-omit-frame-pointer" \
	    SAN="-fsanitize=address,undefined -fno-sanitize-recover=all" test

PREFIX  ?= /usr/local
DESTDIR ?=
VERSION := $(shell sed -n 's/^\#define BSPRAY_VERSION_STRING "\(.*\)"/\1/p' include/bspray/bspray.h)

# A static library: the .pc file's Libs carry its dependencies, so a plain
# `pkg-config --libs bspray` links (with or without --static).
install: $(LIB) $(CLI)
	install -d $(DESTDIR)$(PREFIX)/lib/pkgconfig $(DESTDIR)$(PREFIX)/include/bspray \
	    $(DESTDIR)$(PREFIX)/bin
	install -m 644 $(LIB) $(DESTDIR)$(PREFIX)/lib/
	install -m 644 include/bspray/*.h $(DESTDIR)$(PREFIX)/include/bspray/
	install -m 755 $(CLI) $(DESTDIR)$(PREFIX)/bin/
	printf '%s\n' 'prefix=$(PREFIX)' 'libdir=$${prefix}/lib' 'includedir=$${prefix}/include' '' \
	    'Name: bspray' \
	    'Description: exact ray shooting with adaptive BSP trees (kd-trees)' \
	    'Version: $(VERSION)' \
	    'Cflags: -I$${includedir}' \
	    'Libs: -L$${libdir} -lbspray -lpng -lz -lm -pthread' \
	    > $(DESTDIR)$(PREFIX)/lib/pkgconfig/bspray.pc

clean:
	rm -rf build build-asan build-clang out

-include $(LIB_OBJ:.o=.d) $(TEST_OBJ:.o=.d) $(CLI_OBJ:.o=.d) $(EMBREE_OBJ:.o=.d)
