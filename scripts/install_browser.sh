#!/usr/bin/env bash
# Part of the README's test command: make sure a Chromium is present for the browser
# test of the HTML report (Debian's package, installed when running as root with
# apt-get). Without one the browser test is skipped, except in CI, where it fails.
set -euo pipefail
if ! command -v chromium >/dev/null 2>&1; then
  if [ "$(id -u)" = 0 ] && command -v apt-get >/dev/null 2>&1; then
    apt-get update -qq
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq chromium
  else
    echo "note: no Chromium and no root apt-get here: the browser test will be skipped" >&2
  fi
fi
