#!/usr/bin/env bash
# Build tf2_msgs (the /tf message, TFMessage) from tools/ros_interfaces/tf2_msgs and install it into a virtual
# environment, for a PyPI-only install: PyPI carries rclpy and the common message packages as ros-jazzy-*
# wheels but not tf2_msgs. Run by tools/bootstrap.sh; usage: build.sh VENV.
#
# Does nothing when tf2_msgs already imports in VENV (a ROS install's own tf2_msgs, or an earlier build).
# Otherwise, in a throwaway folder (out/tf2_msgs-build, emptied but for its log after a success): a build
# environment with the rosidl generators, ament CMake, CMake and Ninja from PyPI (requirements-build.txt),
# a CMake build of the package, an install into a staging prefix, then a copy of the staging prefix into VENV
# (libraries to VENV/lib next to the ros-jazzy wheels' own, found the same way at run time; the Python
# package to VENV's site-packages; the ament index entries to VENV/share).
# Python's C headers: from the interpreter's include folder (SMARTICLE_PYTHON_INCLUDE overrides it); when
# Python.h is not there they are fetched without root from the distribution's libpythonX.Y-dev package
# (apt-get download, dpkg-deb -x) into the build folder.
# A failed build does not stop the set-up: it prints one line (what failed, where the log is), writes it to
# VENV/.tf2_msgs-unavailable (the /tf test's skip reason) and exits 1; the nodes then run without /tf.
set -uo pipefail
HERE="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
ROOT="$(cd "$HERE/../.." && pwd)"
VENV="$(cd "${1:?usage: build.sh VENV}" && pwd)"
UNAVAILABLE="$VENV/.tf2_msgs-unavailable"

if "$VENV/bin/python" -c 'import tf2_msgs.msg' >/dev/null 2>&1; then
  rm -f "$UNAVAILABLE"
  exit 0
fi

BUILD="${SMARTICLE_TF2_MSGS_BUILD:-$ROOT/out/tf2_msgs-build}"
LOG="$BUILD/build.log"
rm -rf "$BUILD"
mkdir -p "$BUILD"
echo "[bootstrap] building tf2_msgs (the /tf message, not on PyPI) from tools/ros_interfaces into $VENV" \
     "(about a minute; log: $LOG)"
t0=$SECONDS

steps() {
  set -euo pipefail
  local bvenv="$BUILD/venv" py ver inc np machine
  echo "== step: build environment (requirements-build.txt)" >&2
  "$VENV/bin/python" -m venv "$bvenv"
  "$bvenv/bin/python" -m pip install -q --no-compile -r "$HERE/requirements-build.txt"
  py="$bvenv/bin/python"
  ver="$("$py" -c 'import sys; print(f"{sys.version_info[0]}.{sys.version_info[1]}")')"

  echo "== step: Python headers" >&2
  inc="${SMARTICLE_PYTHON_INCLUDE:-$("$py" -c "import sysconfig; print(sysconfig.get_paths()['include'])")}"
  if [ ! -f "$inc/Python.h" ]; then
    echo "no Python.h in $inc: fetching libpython$ver-dev with apt-get download" >&2
    mkdir -p "$BUILD/deb" "$BUILD/python-headers"
    (cd "$BUILD/deb" && apt-get download "libpython$ver-dev")
    dpkg-deb -x "$BUILD"/deb/libpython"$ver"-dev_*.deb "$BUILD/python-headers"
    inc="$BUILD/python-headers/usr/include/python$ver"
    # Debian's pyconfig.h includes the multiarch one by <triplet/pythonX.Y/pyconfig.h>: put that one in its place
    machine="$(gcc -dumpmachine 2>/dev/null || true)"
    if [ -n "$machine" ] && [ -f "$BUILD/python-headers/usr/include/$machine/python$ver/pyconfig.h" ]; then
      cp "$BUILD/python-headers/usr/include/$machine/python$ver/pyconfig.h" "$inc/pyconfig.h"
    fi
    [ -f "$inc/Python.h" ] || { echo "libpython$ver-dev has no $inc/Python.h" >&2; return 1; }
  fi
  echo "Python headers: $inc" >&2
  np="$("$py" -c 'import numpy; print(numpy.get_include())')"

  echo "== step: CMake files of the ros-jazzy wheels" >&2
  # the wheels' exported CMake targets name the wheel builder's Python and numpy include folders
  { grep -rlE '/opt/python/cp3[0-9]+-cp3[0-9]+' "$bvenv/share" --include='*.cmake' || true; } | xargs -r sed -i -E \
      -e "s#/opt/python/cp3[0-9]+-cp3[0-9]+/lib/python3\.[0-9]+/site-packages/numpy/(_core|core)/include#$np#g" \
      -e "s#/opt/python/cp3[0-9]+-cp3[0-9]+/include/python3\.[0-9]+#$inc#g"

  echo "== step: cmake configure, build, install" >&2
  export PATH="$bvenv/bin:$PATH" AMENT_PREFIX_PATH="$bvenv" CMAKE_PREFIX_PATH="$bvenv" \
         LD_LIBRARY_PATH="$bvenv/lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}"
  cmake --version >&2
  cmake -S "$HERE/tf2_msgs" -B "$BUILD/build" -G Ninja -DCMAKE_BUILD_TYPE=Release -DBUILD_TESTING=OFF \
        -DCMAKE_INSTALL_PREFIX="$BUILD/stage" -DPython3_EXECUTABLE="$py" -DPython3_INCLUDE_DIR="$inc" \
        -DPython3_NumPy_INCLUDE_DIR="$np" -DCMAKE_EXPORT_COMPILE_COMMANDS=ON
  cmake --build "$BUILD/build" -- -v
  cmake --install "$BUILD/build"

  echo "== step: install into $VENV" >&2
  [ -d "$BUILD/stage/lib/python$ver/site-packages/tf2_msgs" ] || {
    echo "no tf2_msgs Python package in $BUILD/stage/lib/python$ver/site-packages" >&2; return 1; }
  cp -a "$BUILD/stage/." "$VENV/"
  "$VENV/bin/python" -c 'from tf2_msgs.msg import TFMessage; TFMessage(transforms=[])'
}

(steps) >"$LOG" 2>&1
status=$?
if [ "$status" -ne 0 ]; then
  step="$(grep '^== step: ' "$LOG" | tail -n 1 | cut -c 10-)"
  line="tf2_msgs build failed at '$step' (log: $LOG): the nodes will not publish /tf"
  echo "[bootstrap] $line" >&2
  echo "$line" > "$UNAVAILABLE"
  exit 1
fi
rm -f "$UNAVAILABLE"
find "$BUILD" -mindepth 1 -maxdepth 1 ! -name build.log -exec rm -rf {} +     # keeps the log
echo "[bootstrap] tf2_msgs built and installed in $((SECONDS - t0)) s"
