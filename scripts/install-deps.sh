#!/bin/sh
# install-deps.sh: installs the Debian packages saarsim builds and runs with.
# Called by `make` only when a dependency is missing (see Makefile, deps
# stamp); safe to run by hand. Needs root or sudo; says so clearly otherwise.
set -eu

PKGS="build-essential pkg-config libopenimageio-dev openimageio-tools \
libyaml-dev zlib1g-dev libassimp-dev libcriterion-dev gnuplot-nox parallel rsync python3"

missing=""
for p in $PKGS; do
	if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "ok installed"; then
		missing="$missing $p"
	fi
done
if [ -z "$missing" ]; then
	echo "install-deps: all packages present"
	exit 0
fi

echo "install-deps: installing missing Debian packages:$missing"
if [ "$(id -u)" -eq 0 ]; then
	SUDO=""
elif command -v sudo >/dev/null 2>&1 && sudo -n true 2>/dev/null; then
	SUDO="sudo -n"
else
	echo "install-deps: error: need root or passwordless sudo to install:$missing" >&2
	echo "install-deps: run as root: apt-get install -y$missing" >&2
	exit 1
fi
export DEBIAN_FRONTEND=noninteractive
$SUDO apt-get update -qq || { echo "install-deps: error: apt-get update failed" >&2; exit 1; }
# shellcheck disable=SC2086
$SUDO apt-get install -y -qq --no-install-recommends $missing ||
	{ echo "install-deps: error: apt-get install failed for:$missing" >&2; exit 1; }
echo "install-deps: done"
