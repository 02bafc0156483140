#!/usr/bin/env bash
# Build Project Chrono's core library and the project's reference driver into a local folder.
#
#   tools/chrono_reference/build_chrono.sh SOURCE [PREFIX]
#
# SOURCE  a Chrono 10 source tree or its tarball (.tgz / .tar.gz). Either Chrono's own checkout (the
#         folder holding CMakeLists.txt and src/chrono) or a folder holding chrono/ with optional
#         eigen3/ and cccl/ (Eigen and CCCL/Thrust headers) beside it, which is what the core-only
#         tarball unpacks to. Without a bundled Eigen the system's (libeigen3-dev) is used.
# PREFIX  where everything goes (default: .chrono/ at the repository root, gitignored):
#           PREFIX/src     the unpacked tarball (tarball input only)
#           PREFIX/build   Chrono's build tree (lib/libChrono_core.so)
#           PREFIX/driver  the reference driver (smarticle_chrono)
#
# Environment: JOBS (parallel jobs, default 2), NICE (niceness, default 15). Chrono's core takes about
# 20 minutes on 2 cores; a rebuild after the first only rebuilds what changed.
set -euo pipefail

usage() { echo "usage: $0 SOURCE [PREFIX]   (SOURCE: a Chrono 10 source tree or its tarball)" >&2; exit 2; }
[ $# -ge 1 ] && [ $# -le 2 ] || usage

here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
repo="$(cd "$here/../.." && pwd)"
source_arg="$1"
prefix="${2:-$repo/.chrono}"
jobs="${JOBS:-2}"
niceness="${NICE:-15}"

for tool in cmake g++; do
    command -v "$tool" >/dev/null || { echo "error: $tool is not installed" >&2; exit 1; }
done
if command -v ninja >/dev/null; then generator=Ninja; else generator="Unix Makefiles"; fi

mkdir -p "$prefix"
prefix="$(cd "$prefix" && pwd)"

# Locate (or unpack) the source.
if [ -f "$source_arg" ]; then
    case "$source_arg" in
        *.tgz|*.tar.gz) ;;
        *) echo "error: $source_arg is a file but not a .tgz/.tar.gz tarball" >&2; exit 1 ;;
    esac
    stamp="$prefix/src/.unpacked-from"
    if [ ! -f "$stamp" ] || [ "$(cat "$stamp")" != "$(cd "$(dirname "$source_arg")" && pwd)/$(basename "$source_arg")" ]; then
        echo "unpacking $source_arg into $prefix/src"
        rm -rf "$prefix/src" && mkdir -p "$prefix/src"
        tar xzf "$source_arg" -C "$prefix/src"
        echo "$(cd "$(dirname "$source_arg")" && pwd)/$(basename "$source_arg")" > "$stamp"
    fi
    top="$prefix/src"
elif [ -d "$source_arg" ]; then
    top="$(cd "$source_arg" && pwd)"
else
    echo "error: $source_arg is neither a Chrono source tree nor a tarball" >&2; exit 1
fi

if [ -f "$top/chrono/CMakeLists.txt" ] && [ -d "$top/chrono/src/chrono" ]; then
    chrono_src="$top/chrono"; extras="$top"
elif [ -f "$top/CMakeLists.txt" ] && [ -d "$top/src/chrono" ]; then
    chrono_src="$top"; extras="$(dirname "$top")"
else
    echo "error: no Chrono source in $source_arg (expected CMakeLists.txt and src/chrono, or chrono/ holding them)" >&2
    exit 1
fi
if [ -d "$extras/eigen3/Eigen" ]; then eigen="$extras/eigen3"
elif [ -d /usr/include/eigen3/Eigen ]; then eigen=/usr/include/eigen3
else echo "error: no Eigen headers (bundled eigen3/ or libeigen3-dev)" >&2; exit 1
fi
thrust_args=()
cccl=""
if [ -d "$extras/cccl/thrust" ]; then cccl="$extras/cccl"; thrust_args=(-DTHRUST_INCLUDE_DIR="$cccl"); fi

build="$prefix/build"
echo "Chrono source: $chrono_src"
echo "Eigen: $eigen   Thrust: ${cccl:-none}   build: $build   jobs: $jobs   nice: $niceness"
start=$(date +%s)
nice -n "$niceness" cmake -S "$chrono_src" -B "$build" -G "$generator" -DCMAKE_BUILD_TYPE=Release \
    -DBUILD_DEMOS=OFF -DBUILD_TESTING=OFF -DBUILD_BENCHMARKING=OFF -DCH_ENABLE_YAML=OFF \
    -DCH_ENABLE_OPENMP=OFF -DCMAKE_EXPORT_COMPILE_COMMANDS=ON \
    -DEIGEN3_INCLUDE_DIR="$eigen" "${thrust_args[@]}"
nice -n "$niceness" cmake --build "$build" --target Chrono_core -j "$jobs"
echo "Chrono core built in $(( $(date +%s) - start )) s: $build/lib"

# The project's driver, linked against that build.
nice -n "$niceness" cmake -S "$here" -B "$prefix/driver" -G "$generator" -DCMAKE_BUILD_TYPE=Release \
    -DCHRONO_BUILD_DIR="$build" -DEIGEN3_INCLUDE_DIR="$eigen" \
    -DTHRUST_INCLUDE_DIR="$cccl"
nice -n "$niceness" cmake --build "$prefix/driver" -j "$jobs"
echo "driver: $prefix/driver/smarticle_chrono"
