#!/usr/bin/env bash
# ctest claims: every figure the documents quote from a committed result set is what its generator
# computes from that set (scripts/claims.py; docs/claims.md). Seconds. Skipped (exit 77) without
# python3, except under CI=true, where a missing python3 fails.
set -euo pipefail
cd "${0%/*}/.."
if ! command -v python3 >/dev/null 2>&1; then
  if [ -n "${CI:-}" ]; then
    echo "claims-check: python3 is missing (CI=${CI}): install it (scripts/install-deps.sh)" >&2
    exit 1
  fi
  echo "claims-check: python3 is missing: skipped (scripts/install-deps.sh installs it)" >&2
  exit 77
fi
exec python3 scripts/claims.py
