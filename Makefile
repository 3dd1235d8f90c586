# polydem top-level build. `make deps` installs the Debian packages, `make` builds build/polydem,
# `make check` builds and runs every test, `make check SANITIZE=1` runs them under ASan+UBSan.

# clang where there is one (`make deps` installs it): the overlap's host code, which the CLI, the
# tests and bench/overlap run, takes 13-15 % less time than with gcc 12 and gives the same bits
# (bench/RESULTS.md, 2026-12-07, fourth session). After `make clean`, `make CC=gcc` uses gcc.
ifeq ($(origin CC),default)
CC := $(if $(shell command -v clang 2>/dev/null),clang,cc)
endif
ifeq ($(SANITIZE),1)
BUILD := build/san
SANFLAGS := -fsanitize=address,undefined -fno-omit-frame-pointer -fno-sanitize-recover=undefined
else
BUILD := build
SANFLAGS :=
endif

# -ffp-contract=off: the OpenCL kernels are built with FP_CONTRACT OFF too, so host and device
# round the same operations the same way (the overlap paths must agree to 1e-12).
# -gdwarf-4: valgrind 3.19 (Debian 12) gives up on clang 14's default DWARF 5 ("possibly corrupted
# debuginfo"), and callgrind is how bench/RESULTS.md counts the overlap's instructions
CFLAGS ?= -O2 -g -gdwarf-4
CFLAGS += -std=c11 -D_POSIX_C_SOURCE=200809L -Wall -Wextra -Werror -ffp-contract=off \
          -Iengine -Ikernels -I$(BUILD)/gen -I/usr/include/hdf5/serial $(SANFLAGS)
# Debian's serial HDF5 lives under hdf5/serial
LDLIBS := -lOpenCL -ljansson -lhdf5_serial -lm
LDFLAGS += $(SANFLAGS)

ENGINE_SRC := $(wildcard engine/*.c)
ENGINE_OBJ := $(patsubst engine/%.c,$(BUILD)/engine/%.o,$(ENGINE_SRC))
CL_SRC := $(wildcard kernels/*.cl)
CL_HDR := $(wildcard kernels/*.h)
CL_GEN := $(BUILD)/gen/cl_sources.h

UNIT_SRC := $(wildcard tests/unit/test_*.c) $(wildcard tests/physics/test_*.c)
UNIT_BIN := $(patsubst tests/%.c,$(BUILD)/tests/%,$(UNIT_SRC))

BENCH_SRC := $(wildcard bench/*.c)
BENCH_BIN := $(patsubst bench/%.c,$(BUILD)/bench/%,$(BENCH_SRC))

.PHONY: all deps check check-build bench format format-check clean
all: $(BUILD)/polydem

DEB_PACKAGES := build-essential clang ocl-icd-opencl-dev opencl-c-headers pocl-opencl-icd clinfo \
                clang-format libjansson-dev libhdf5-dev hdf5-tools python3-jsonschema \
                libxml2-utils
# components add their rules, tests and packages here (server/server.mk: polydemd)
-include server/server.mk
-include studies/studies.mk
-include clients/clients.mk

deps:
	@sh tools/install_deps.sh $(DEB_PACKAGES)

$(CL_GEN): $(CL_SRC) $(CL_HDR) tools/embed_cl.sh
	@mkdir -p $(dir $@)
	sh tools/embed_cl.sh $(CL_SRC) > $@.tmp && mv $@.tmp $@

$(BUILD)/engine/%.o: engine/%.c $(wildcard engine/*.h) $(CL_HDR) $(CL_GEN)
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -c $< -o $@

$(BUILD)/libpolydem.a: $(ENGINE_OBJ)
	rm -f $@ && ar rcs $@ $^

$(BUILD)/polydem: cli/polydem.c $(BUILD)/libpolydem.a
	$(CC) $(CFLAGS) $< $(BUILD)/libpolydem.a $(LDFLAGS) $(LDLIBS) -o $@

$(BUILD)/tests/%: tests/%.c $(wildcard tests/*.h) $(BUILD)/libpolydem.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) -Itests $< $(BUILD)/libpolydem.a $(LDFLAGS) $(LDLIBS) -o $@

$(BUILD)/bench/%: bench/%.c $(wildcard bench/*.h) $(wildcard tests/*.h) $(BUILD)/libpolydem.a
	@mkdir -p $(dir $@)
	$(CC) $(CFLAGS) $< $(BUILD)/libpolydem.a $(LDFLAGS) $(LDLIBS) -o $@

# `make check` builds on every core (JOBS=1 for one at a time; a `make -jN` given by the caller
# is kept), then runs the tests one by one; components add what the tests need to check-build
# (server/server.mk: polydemd)
JOBS ?= $(shell nproc 2>/dev/null || echo 1)
check:
	@$(MAKE) --no-print-directory $(if $(findstring jobserver,$(MAKEFLAGS)),,-j$(JOBS)) check-build
	@BUILD=$(BUILD) sh tests/run.sh $(UNIT_BIN)

check-build: $(BUILD)/polydem $(UNIT_BIN) $(BENCH_BIN)

bench: $(BUILD)/polydem $(BENCH_BIN)
	$(BUILD)/bench/overlap

format:
	clang-format -i engine/*.c engine/*.h kernels/*.h kernels/*.cl cli/*.c tests/*.h tests/*/*.c bench/*.c

format-check:
	@clang-format --dry-run -Werror engine/*.c engine/*.h kernels/*.h kernels/*.cl cli/*.c tests/*.h tests/*/*.c bench/*.c

clean:
	rm -rf build
