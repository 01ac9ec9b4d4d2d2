#!/usr/bin/env sh
# The Python package's tests: the package built by pip (maturin) into a virtual environment
# under target/, then its tests, which also run the command built by `cargo test --release`.
set -eu
cd "$(dirname "$0")/.."
python3 -m venv target/python-env
target/python-env/bin/python -m pip install -q --disable-pip-version-check ./python
target/python-env/bin/python -m unittest discover -s python/tests -v
