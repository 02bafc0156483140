#!/usr/bin/env bash
# The main job: a run of the whole stack with its default settings (sets up .venv first when needed).
set -euo pipefail
ROOT="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
source "$ROOT/tools/bootstrap.sh"
cd "$ROOT"
exec python -m smarticle_bringup.demo "$@"
