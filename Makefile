# Thin wrappers; README.md names two of them (demo, test). Everything builds into build/.
SHELL := /bin/bash
.SHELLFLAGS := -e -o pipefail -c
REPO := $(CURDIR)
BUILD := $(REPO)/build
CATKIN_BUILD := $(BUILD)/catkin
DEVEL := $(BUILD)/devel
VENV := $(REPO)/.venv
OUT ?= $(REPO)/out
JOBS ?= $(shell nproc)

# Debian's interpreter and tools first: the pyenv python3 on some PATHs cannot see ROS.
export PATH := $(VENV)/bin:/usr/bin:$(PATH)
export ROS_HOME := $(BUILD)/ros_home
export FOLLOW_BOT_VENV := $(VENV)
ROSENV := source $(DEVEL)/setup.bash &&

.PHONY: deps nodes build demo test test-full lint format docs bench fuzz clean

deps:
	tools/install_deps.sh

# The nodes, nodelets and tools (catkin's default target): what `make demo` needs.
nodes: deps
	mkdir -p $(CATKIN_BUILD)
	touch $(BUILD)/CATKIN_IGNORE $(BUILD)/COLCON_IGNORE
	cd $(CATKIN_BUILD) && cmake $(REPO) -DCATKIN_DEVEL_PREFIX=$(DEVEL) \
	  -DCMAKE_BUILD_TYPE=Release -DPYTHON_EXECUTABLE=/usr/bin/python3 \
	  -DCMAKE_EXPORT_COMPILE_COMMANDS=ON >/dev/null
	$(MAKE) -C $(CATKIN_BUILD) -j$(JOBS) --no-print-directory

# Everything, with the gtest binaries.
build: nodes
	$(MAKE) -C $(CATKIN_BUILD) -j$(JOBS) --no-print-directory tests

# A headless lap of the course with the follower: prints the score, writes the plot and video.
demo: nodes
	$(ROSENV) rosrun harness run_scenario worlds/scenarios/follower.yaml \
	  --select follower/lap_default --out $(OUT) --video
	@echo "demo: plot  $(OUT)/follower/lap_default/run.png"
	@echo "demo: video $(OUT)/follower/lap_default/camera.mp4"

# Style and static checks; clang-tidy needs the build's compile commands and generated headers.
lint: nodes
	tools/lint.sh

format: deps
	tools/lint.sh --fix

# Rewrites the parameter tables of the READMEs and manuals (doc/*.md) from the .cfg files
# (tests/repo/test_param_tables.py checks them).
docs:
	/usr/bin/python3 tools/param_tables.py --write

# test: every suite, with every fault run of the scenario families and one run of each other family;
# test-full: every run of every scenario family's matrix too.
test: build lint
	tools/run_tests.sh

test-full: build lint
	FULL=1 tools/run_tests.sh

bench: build
	$(MAKE) -C $(CATKIN_BUILD) -j$(JOBS) --no-print-directory follow_bot_bench_nodelets
	$(ROSENV) tools/bench.sh

# Seeded storm of random and malformed messages, 10,000 per node; prints counts per node and
# writes out/fuzz.json. Exit 1 when a node died, answered wrong or sent a bad Twist.
fuzz: build
	mkdir -p $(OUT)
	$(ROSENV) rosrun harness fuzz --messages 10000 --seed 12 --json $(OUT)/fuzz.json

clean:
	rm -rf $(BUILD) $(OUT)
