# The README's two commands: `make render` and `make test`. Both set up a fresh machine
# first, saying what they do: `render` only what rendering needs, `test` also the test tools
# and Chromium (scripts/ci/setup.sh).
VENV := .venv
BIN := $(VENV)/bin

.PHONY: setup setup-test render test lint bench
setup:
	VENV=$(VENV) scripts/ci/setup.sh render

setup-test:
	VENV=$(VENV) scripts/ci/setup.sh test

render: setup
	mkdir -p out
	$(BIN)/gi render cornell -o out/cornell.exr -o out/cornell.png

lint: setup-test
	python3 scripts/ci/check_layers.py
	python3 scripts/ci/architecture.py --check
	cargo fmt --all -- --check
	cargo clippy --workspace --all-targets -- -D warnings
	RUSTDOCFLAGS="-D warnings" cargo doc --workspace --no-deps
	$(BIN)/ruff check python tests scripts
	$(BIN)/ruff format --check python tests scripts

test: lint
	cargo test --workspace
	$(BIN)/python -m pytest

bench:
	cargo bench -p gi-core
