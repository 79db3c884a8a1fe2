#!/usr/bin/env bash
# One entry point for a fresh Debian 12 machine (as root, or with sudo):
#   tools/bootstrap.sh demo   install what is missing, build, run the main job
#   tools/bootstrap.sh test   install what is missing, build, run every test
# Idempotent: when everything is there it only builds and runs.
set -euo pipefail
cd "$(dirname "$0")/.."
ROOT=$PWD
job=${1:-}
case "$job" in
  demo|test|setup) ;;
  *) echo "usage: $0 demo|test|setup" >&2; exit 2 ;;
esac

log() { printf '\033[1m[bootstrap]\033[0m %s\n' "$*"; }

# ---- Debian packages --------------------------------------------------------
APT_PACKAGES=(
  cmake ninja-build g++ gcc make git
  libeigen3-dev libgtest-dev libtomlplusplus-dev
  gcc-arm-none-eabi libnewlib-arm-none-eabi binutils-arm-none-eabi
  qemu-system-arm
  can-utils
  cppcheck clang-tidy clang-format
  clang-14 libfuzzer-14-dev libclang-rt-14-dev
  qemu-system-x86 busybox-static linux-image-amd64 cpio kmod iproute2
  python3 python3-venv python3-dev ca-certificates
)
missing=()
for p in "${APT_PACKAGES[@]}"; do
  if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q 'install ok installed'; then
    missing+=("$p")
  fi
done
if ((${#missing[@]})); then
  SUDO=""
  [ "$(id -u)" -eq 0 ] || SUDO=sudo
  log "installing Debian packages: ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

# ---- Python tools (project-local venv, from PyPI) ---------------------------
VENV=$ROOT/.venv
REQ=$ROOT/tools/requirements.txt
stamp=$VENV/.requirements.sha256
want=$(sha256sum "$REQ" | cut -d' ' -f1)
if [ ! -x "$VENV/bin/python" ] || [ "$(cat "$stamp" 2>/dev/null)" != "$want" ]; then
  log "creating Python venv in .venv (tools/requirements.txt)"
  /usr/bin/python3 -m venv "$VENV"
  "$VENV/bin/pip" install -q --disable-pip-version-check -r "$REQ"
  echo "$want" > "$stamp"
fi
# mdtool (tools/mdtool): the host package with the SIL extension, built from
# this tree's sources. Re-installed when its inputs change: the commit and
# the content of the folders it compiles or ships (a stamp of their hashes;
# a few milliseconds when nothing changed).
mdtool_stamp=$VENV/.mdtool.sha256
mdtool_want=$( { git -C "$ROOT" rev-parse HEAD 2>/dev/null || true
  find "$ROOT/firmware" "$ROOT/hal" "$ROOT/sim" "$ROOT/tools/cmake" "$ROOT/tools/mdtool" \
       -path "$ROOT/tools/mdtool/build" -prune -o -name __pycache__ -prune -o -type f -print0 |
    sort -z | xargs -0 sha256sum; } | sha256sum | cut -d' ' -f1)
if [ "$(cat "$mdtool_stamp" 2>/dev/null)" != "$mdtool_want" ] || ! "$VENV/bin/python" -c 'import mdtool._sil' 2>/dev/null; then
  log "installing mdtool (tools/mdtool) into .venv"
  "$VENV/bin/pip" install -q --disable-pip-version-check --no-build-isolation "$ROOT/tools/mdtool"
  echo "$mdtool_want" > "$mdtool_stamp"
fi
export PATH=$VENV/bin:$PATH
export MC_PYTHON=$VENV/bin/python

# ---- SocketCAN VM (this kernel may lack CAN; see tools/vm/mc_vm.sh) ---------
# Builds and caches a busybox initramfs with Debian's can/vcan modules in
# .cache/vm; a no-op when the cached image is current.
"$ROOT/tools/vm/mc_vm.sh" prepare

JOBS=$(nproc)

build() { # preset
  cmake --preset "$1" >/dev/null
  cmake --build --preset "$1" -j "$JOBS"
}

case "$job" in
  setup)
    log "set-up complete"
    ;;
  demo)
    exec "$ROOT/tools/demo.sh"
    ;;
  test)
    exec "$ROOT/tools/test.sh"
    ;;
esac
