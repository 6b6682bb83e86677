#!/usr/bin/env bash
# Install Debian packages for the set-up scripts (ensure_libclang.sh, ensure_openmpi.sh): as
# root, else through sudo; on failure once more after refreshing the package lists.
#
# Usage: tools/apt_install.sh LABEL PACKAGE...   (LABEL prefixes the error message)
set -euo pipefail
label=$1
shift
sudo=""
[ "$(id -u)" = 0 ] || sudo=sudo
export DEBIAN_FRONTEND=noninteractive
if ! $sudo apt-get install -y -q "$@"; then
  $sudo apt-get update -q && $sudo apt-get install -y -q "$@" || {
    echo "$label: could not install $*; install them (apt-get install $*) and rerun" >&2
    exit 1
  }
fi
