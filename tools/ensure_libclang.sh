#!/usr/bin/env bash
# Make sure bindgen (run by rsmpi's mpi-sys in every build and by rust-fmi's fmi-sys in
# `make test-import`) finds a libclang it can load, and install Debian's libclang-dev when it
# cannot.
#
# What counts is what clang-sys (bindgen's loader) accepts: a file named libclang.so,
# libclang-N.so, libclang.so.N or libclang-N.so.N in LIBCLANG_PATH, `llvm-config --libdir`,
# /usr/lib*, /usr/local/lib* or /usr/lib/llvm-*/lib (clang-sys's build/common.rs search list).
# libclang-cpp.so.N is NOT one of them: it is LLVM's C++ library, which Debian installs with
# llvm-N-dev and other packages, and which clang-sys skips. An earlier check globbed
# libclang*.so* and took that file for libclang, so `make test` said "present" and then
# bindgen panicked with "Unable to find libclang" on a fresh machine.
# bindgen also needs clang's own resource headers (stddef.h, from libclang-common-N-dev, a
# dependency of libclang-dev); a runtime-only libclang1-N is not enough.
#
# Usage: tools/ensure_libclang.sh [--check]   (--check: report only, exit 1 when missing)
set -euo pipefail

dirs=()
[ -n "${LIBCLANG_PATH:-}" ] && dirs+=("$LIBCLANG_PATH")
if command -v llvm-config >/dev/null 2>&1; then dirs+=("$(llvm-config --libdir)"); fi
for d in /usr/lib/llvm-*/lib /usr/lib /usr/lib64 /usr/lib/x86_64-linux-gnu /usr/local/lib /usr/local/lib64; do
  [ -d "$d" ] && dirs+=("$d")
done

library=""
for d in "${dirs[@]}"; do
  for f in "$d"/libclang.so "$d"/libclang-[0-9]*.so "$d"/libclang.so.[0-9]* "$d"/libclang-[0-9]*.so.[0-9]*; do
    if [ -e "$f" ]; then library="$f"; break 2; fi
  done
done
headers=$(ls /usr/lib/llvm-*/lib/clang/*/include/stddef.h /usr/local/lib/clang/*/include/stddef.h 2>/dev/null | head -n1 || true)

if [ -n "$library" ] && [ -n "$headers" ]; then
  echo "libclang: present ($library, headers $(dirname "$headers"))"
  exit 0
fi
missing=$([ -z "$library" ] && echo "no libclang.so / libclang-N.so* that bindgen loads" || echo "no clang resource headers (stddef.h)")
if [ "${1:-}" = "--check" ]; then
  echo "libclang: missing ($missing)"
  exit 1
fi

echo "libclang: $missing; installing Debian's libclang-dev (rsmpi's mpi-sys and rust-fmi's fmi-sys run bindgen at build time)"
"$(dirname "$0")/apt_install.sh" "libclang" libclang-dev
exec "$0" --check
