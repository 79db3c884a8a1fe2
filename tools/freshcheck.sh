#!/usr/bin/env bash
# tools/freshcheck.sh [--keep] [--dir DIR] [--jobs "demo test"] [--busy] [--rev REV]
#
# Proves that the README's two commands work on a truly fresh Debian 12
# machine, not just on this one (where a package installed by hand hides a
# missing install step): makes a minimal Debian 12 root with debootstrap from
# Debian's archive, clones the committed tree (REV, default HEAD) into it, and
# runs, as root inside it, exactly what the README says:
#     tools/bootstrap.sh demo
#     tools/bootstrap.sh test
# Each must exit 0. The log of each is kept in DIR/../freshcheck-<job>.log,
# and a machine-readable line reports the times:
#     [freshcheck] {"debootstrap_s": .., "demo_s": .., "test_s": .., "rev": ..}
#
# Needs: root (chroot, mounts), debootstrap (installed here when missing, from
# Debian's packages), network access to Debian's archive and PyPI as this
# machine has it, about 6 GiB of disk. The root gets only what a fresh
# machine would need to reach those: this machine's apt sources and apt
# settings, its local CA certificates (an intercepting proxy's CA: without
# them pip fails with CERTIFICATE_VERIFY_FAILED) and /etc/pip.conf. /proc,
# /sys, /dev and /dev/pts are bound into the root (the suite starts QEMU and
# needs ptys); everything is unmounted and the root deleted at the end unless
# --keep. --busy keeps one core busy (`yes > /dev/null`) while the suite
# runs, as a shared machine would.
#
# Measured on the 2-core development machine: debootstrap about 30 s, the demo
# (packages included) about 4 min, the test suite about 20 min; the exact
# times of a run are in its [freshcheck] line.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
REPO=$(cd "$HERE/.." && pwd)
DIR=/var/tmp/mc-freshcheck/root
JOBS="demo test"
KEEP=0 BUSY=0 REV=HEAD
while [ $# -gt 0 ]; do
  case "$1" in
    --keep) KEEP=1 ;;
    --busy) BUSY=1 ;;
    --dir) DIR=$2; shift ;;
    --jobs) JOBS=$2; shift ;;
    --rev) REV=$2; shift ;;
    -h|--help) sed -n '2,30p' "$0"; exit 0 ;;
    *) echo "freshcheck: unknown option $1" >&2; exit 2 ;;
  esac
  shift
done
for j in $JOBS; do
  case "$j" in demo|test) ;; *) echo "freshcheck: --jobs takes demo and/or test" >&2; exit 2 ;; esac
done
[ "$(id -u)" -eq 0 ] || { echo "freshcheck: must run as root (debootstrap, chroot, mounts)" >&2; exit 2; }
log() { printf '\033[1m[freshcheck]\033[0m %s\n' "$*"; }
SHA=$(git -C "$REPO" rev-parse --verify "$REV^{commit}")
LOGDIR=$(dirname "$DIR")
mkdir -p "$LOGDIR"

if ! command -v debootstrap >/dev/null; then
  log "installing debootstrap (Debian package)"
  apt-get update -qq
  DEBIAN_FRONTEND=noninteractive apt-get install -y -qq --no-install-recommends debootstrap
fi

mounts=()
busy_pid=""
cleanup() {
  [ -z "$busy_pid" ] || kill "$busy_pid" 2>/dev/null || true
  local i
  for ((i = ${#mounts[@]} - 1; i >= 0; i--)); do umount -l "${mounts[i]}" 2>/dev/null || true; done
  if [ "$KEEP" -eq 0 ] && [ -d "$DIR" ]; then rm -rf --one-file-system "$DIR"; fi
}
trap cleanup EXIT

if [ -e "$DIR" ]; then
  # a root left by an earlier --keep run: make sure nothing is still mounted in it
  for m in dev/pts dev sys proc; do umount -l "$DIR/$m" 2>/dev/null || true; done
  rm -rf --one-file-system "$DIR"
fi
mkdir -p "$DIR"
t0=$(date +%s)
log "debootstrap: Debian 12 (bookworm, minbase) into $DIR"
debootstrap --variant=minbase bookworm "$DIR" http://deb.debian.org/debian > "$LOGDIR/freshcheck-debootstrap.log" 2>&1 \
  || { tail -20 "$LOGDIR/freshcheck-debootstrap.log"; exit 1; }
t_deboot=$(( $(date +%s) - t0 ))

# What a fresh machine on this network has besides Debian: the way to the
# archive and PyPI (sources, apt settings, CA certificates, pip's settings).
rm -f "$DIR/etc/apt/sources.list"
for f in /etc/apt/sources.list /etc/apt/sources.list.d/*.list /etc/apt/sources.list.d/*.sources; do
  [ -f "$f" ] && cp "$f" "$DIR$f"
done
for f in /etc/apt/apt.conf.d/*; do
  [ -f "$f" ] && grep -q '^Acquire' "$f" && cp "$f" "$DIR/etc/apt/apt.conf.d/"
done
mkdir -p "$DIR/usr/local/share/ca-certificates"
cp /usr/local/share/ca-certificates/*.crt "$DIR/usr/local/share/ca-certificates/" 2>/dev/null || true
[ -f /etc/pip.conf ] && cp /etc/pip.conf "$DIR/etc/pip.conf"
cp /etc/resolv.conf "$DIR/etc/resolv.conf" 2>/dev/null || true

for m in proc sys dev dev/pts; do
  mount --bind "/$m" "$DIR/$m"
  mounts+=("$DIR/$m")
done

log "fresh clone of $SHA into /root/motordrive"
git clone -q --no-local "$REPO" "$DIR/root/motordrive"
git -C "$DIR/root/motordrive" checkout -q "$SHA"

if [ "$BUSY" -eq 1 ]; then
  yes > /dev/null &
  busy_pid=$!
  log "one core kept busy by pid $busy_pid"
fi

declare -A took
for j in $JOBS; do
  log "running 'tools/bootstrap.sh $j' in the fresh root (log: $LOGDIR/freshcheck-$j.log)"
  t=$(date +%s)
  if ! chroot "$DIR" /usr/bin/env -i PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
      HOME=/root LANG=C.UTF-8 TERM=dumb CI=true \
      /bin/bash -c "cd /root/motordrive && tools/bootstrap.sh $j" > "$LOGDIR/freshcheck-$j.log" 2>&1; then
    tail -40 "$LOGDIR/freshcheck-$j.log"
    log "FAILED: tools/bootstrap.sh $j (full log: $LOGDIR/freshcheck-$j.log)"
    exit 1
  fi
  took[$j]=$(( $(date +%s) - t ))
  tail -5 "$LOGDIR/freshcheck-$j.log"
done

printf '[freshcheck] {"rev": "%s", "debootstrap_s": %d' "$SHA" "$t_deboot"
for j in $JOBS; do printf ', "%s_s": %d' "$j" "${took[$j]}"; done
printf ', "busy": %s}\n' "$([ "$BUSY" -eq 1 ] && echo true || echo false)"
log "passed: the README's commands work on a fresh Debian 12 root"
