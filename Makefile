# Convenience targets; each is the same command the README gives.
.PHONY: setup demo test test-fast bench

setup:
	python3 -m venv .venv && .venv/bin/pip install -q -e ".[test]"

demo: setup
	.venv/bin/python examples/demo_synthetic.py --out out/demo

test:
	bash .ci/run

test-fast: setup
	.venv/bin/python -m pytest -q -m "not slow"

bench: setup
	.venv/bin/python perf/bench_kernels.py
