#!/usr/bin/env bash
# Create (or refresh) the project's virtual environment in .venv and install everything into it:
# the PyPI dependencies from requirements-dev.txt, the ROS 2 packages of the stack and the example controller
# (examples/), editable, and tf2_msgs (the /tf message, not on PyPI), generated from tools/ros_interfaces unless
# tf2_msgs already imports (a ROS install brings its own).
# Sourced by demo.sh and test.sh, or by a user (`source tools/bootstrap.sh`) to put .venv/bin on PATH; safe to
# run again (it only reinstalls when the project files change). Sourcing it changes only PATH and VIRTUAL_ENV:
# the set-up runs in a subshell with its own shell options, so the caller's options (set -e, ...) and variables
# stay as they were, and a failed set-up returns non-zero instead of closing the caller's shell.

_smarticle_root="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
_smarticle_venv="${SMARTICLE_VENV:-$_smarticle_root/.venv}"

(
  set -euo pipefail
  ROOT="$_smarticle_root"
  VENV="$_smarticle_venv"
  PY="${PYTHON:-python3}"
  PACKAGES=(smarticle_common smarticle_driver smarticle_sim smarticle_feedback smarticle_tracking bags/smarticle_bags
            smarticle_experiments smarticle_bringup examples/smarticle_example_controller)

  stamp_of() {
    # everything that changes what gets installed
    (cd "$ROOT" && cat requirements.txt requirements-dev.txt tools/bootstrap.sh tools/ros_interfaces/build.sh \
       "${PACKAGES[@]/%//setup.py}" "${PACKAGES[@]/%//setup.cfg}" | sha256sum | cut -d' ' -f1)
  }

  if [ ! -x "$VENV/bin/python" ]; then
    echo "[bootstrap] creating virtual environment $VENV"
    if ! "$PY" -m venv "$VENV" 2>/dev/null; then
      rm -rf "$VENV"
      if command -v apt-get >/dev/null 2>&1 && [ "$(id -u)" = 0 ]; then
        echo "[bootstrap] python venv module missing: installing Debian's python3-venv"
        apt-get update -qq && apt-get install -y -qq python3-venv >/dev/null
        "$PY" -m venv "$VENV"
      else
        echo "[bootstrap] error: '$PY -m venv' failed; install your distribution's python3-venv package" >&2
        exit 1
      fi
    fi
  fi

  want="$(stamp_of)"
  have="$(cat "$VENV/.smarticle-stamp" 2>/dev/null || true)"
  if [ "$want" != "$have" ]; then
    echo "[bootstrap] installing dependencies into $VENV (the first run takes a few minutes)"
    "$VENV/bin/python" -m pip install -q --upgrade pip
    "$VENV/bin/python" -m pip install -q -r "$ROOT/requirements-dev.txt"
    for p in "${PACKAGES[@]}"; do
      "$VENV/bin/python" -m pip install -q --no-deps --no-build-isolation \
        --config-settings editable_mode=compat -e "$ROOT/$p"
    done
    # a failed build says so in one line and leaves the stack without /tf; the set-up goes on
    bash "$ROOT/tools/ros_interfaces/build.sh" "$VENV" || true
    echo "$want" > "$VENV/.smarticle-stamp"
    echo "[bootstrap] environment ready"
  fi
)
# not `if ( ... )`: bash ignores set -e inside a condition, so the status is read on the next line
_smarticle_status=$?
if [ "$_smarticle_status" = 0 ]; then
  case "$PATH" in
    "$_smarticle_venv/bin:"*) ;;
    *) export PATH="$_smarticle_venv/bin:$PATH" ;;
  esac
  export VIRTUAL_ENV="$_smarticle_venv"
  unset _smarticle_root _smarticle_venv _smarticle_status
else
  echo "[bootstrap] error: the set-up of $_smarticle_venv failed (see the messages above)" >&2
  unset _smarticle_root _smarticle_venv _smarticle_status
  # a failed set-up: non-zero for the caller (demo.sh and test.sh stop there), never an exit of a sourcing shell
  return 1 2>/dev/null || exit 1
fi
