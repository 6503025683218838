#!/usr/bin/env bash
# The test command of the README (and exactly what .ci/run runs): install the test
# extra, make sure a Chromium is present for the browser test of the HTML report
# (Debian's package, installed when running as root with apt-get), then run pytest.
set -euo pipefail
cd "$(dirname "$0")/.."
pip install ".[test]"
if ! command -v chromium >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium
  else
    echo "note: no Chromium and no root apt-get here: the browser test will be skipped" >&2
  fi
fi
python -m pytest
