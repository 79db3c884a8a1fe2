#!/usr/bin/env bash
# Run a shell script on a Linux kernel that has SocketCAN, in a small VM.
#
#   tools/vm/mc_vm.sh prepare           build (or reuse) the cached kernel + initramfs
#   tools/vm/mc_vm.sh run SCRIPT        boot, run SCRIPT (a host path, run with
#                                       /bin/sh in the host's root file system
#                                       shared over 9p), return its exit code
#   tools/vm/mc_vm.sh native            exit 0 if this kernel has vcan itself
#
# The machine's own kernel may lack CAN (CONFIG_CAN unset). The VM boots
# Debian's packaged kernel (linux-image-amd64: vmlinuz in /boot, can, can-raw,
# can-dev, vcan and the virtio 9p modules in /lib/modules) with an initramfs
# made of busybox-static and those modules; qemu-system-x86_64 (TCG) shares
# the host root over virtio-9p, so the guest runs the host's own binaries,
# Python venv and can-utils. Everything comes from Debian packages installed
# by tools/bootstrap.sh (linux-image-amd64 busybox-static qemu-system-x86);
# the initramfs is cached in $MC_VM_CACHE (default <repo>/.cache/vm), keyed
# by kernel version and the content of this directory.
set -euo pipefail
HERE=$(cd "$(dirname "$0")" && pwd)
ROOT=$(cd "$HERE/../.." && pwd)
CACHE=${MC_VM_CACHE:-$ROOT/.cache/vm}
MODULES_ORDER="virtio_ring virtio virtio_pci_legacy_dev virtio_pci_modern_dev virtio_pci
netfs fscache 9pnet 9pnet_virtio 9p can can-raw can-dev vcan"

die() { echo "mc_vm: $*" >&2; exit 2; }

# Newest kernel that has both an image in /boot and the vcan module.
pick_kernel() {
    local v best=""
    for d in /lib/modules/*/; do
        v=$(basename "$d")
        [ -r "/boot/vmlinuz-$v" ] || continue
        [ -n "$(find "$d" -name vcan.ko\* -print -quit 2>/dev/null)" ] || continue
        best=$v
    done
    [ -n "$best" ] || die "no kernel with vcan found: install linux-image-amd64 (see tools/bootstrap.sh)"
    echo "$best"
}

module_path() { # kver name
    local p
    p=$(modinfo -k "$1" -n "$2" 2>/dev/null) || die "module $2 not found for kernel $1"
    echo "$p"
}

prepare() {
    command -v qemu-system-x86_64 >/dev/null || die "qemu-system-x86_64 missing (apt package qemu-system-x86)"
    command -v cpio >/dev/null || die "cpio missing (apt package cpio)"
    command -v modinfo >/dev/null || die "modinfo missing (apt package kmod)"
    local bb=/bin/busybox
    # ldd fails on a static executable: the initramfs has no libc to offer
    [ -x "$bb" ] && ! ldd "$bb" >/dev/null 2>&1 \
        || die "static busybox missing (apt package busybox-static)"
    local kver key dir
    kver=$(pick_kernel)
    key=$(cat "$HERE/mc_vm_init.sh" "$HERE/mc_vm.sh" | sha256sum | cut -c1-12)
    dir=$CACHE/$kver-$key
    if [ ! -s "$dir/initramfs.cpio.gz" ] || [ ! -s "$dir/vmlinuz" ]; then
        local stage
        stage=$(mktemp -d)
        mkdir -p "$stage/bin" "$stage/modules" "$stage/proc" "$stage/sys" "$stage/dev"
        cp "$bb" "$stage/bin/busybox"
        cp "$HERE/mc_vm_init.sh" "$stage/init"
        chmod 755 "$stage/init"
        : > "$stage/modules.order"
        for m in $MODULES_ORDER; do
            local src
            src=$(module_path "$kver" "$m")
            case "$src" in
                *.ko) cp "$src" "$stage/modules/$m.ko" ;;
                *.ko.xz) xz -dc "$src" > "$stage/modules/$m.ko" ;;
                *.ko.zst) zstd -qdc "$src" > "$stage/modules/$m.ko" ;;
                *.ko.gz) gzip -dc "$src" > "$stage/modules/$m.ko" ;;
                *) die "unexpected module file $src" ;;
            esac
            echo "$m" >> "$stage/modules.order"
        done
        mkdir -p "$dir"
        (cd "$stage" && find . | LC_ALL=C sort | cpio -o -H newc --quiet) | gzip -1 > "$dir/initramfs.cpio.gz.part"
        cp "/boot/vmlinuz-$kver" "$dir/vmlinuz.part"
        mv "$dir/initramfs.cpio.gz.part" "$dir/initramfs.cpio.gz"
        mv "$dir/vmlinuz.part" "$dir/vmlinuz"
        rm -rf "$stage"
        # older images (other kernels, other versions of these scripts)
        find "$CACHE" -mindepth 1 -maxdepth 1 -type d ! -path "$dir" -exec rm -rf {} + 2>/dev/null || true
    fi
    echo "$dir"
}

run() { # script
    local script dir rc
    script=$(readlink -f "$1")
    [ -r "$script" ] || die "script $1 not readable"
    case "$script" in *" "*) die "script path must not contain spaces" ;; esac
    dir=$(prepare)
    rm -f "$script.rc"
    # -smp 2 with multi-threaded TCG; nested KVM hangs on these machines.
    timeout "${MC_VM_TIMEOUT:-600}" qemu-system-x86_64 \
        -accel tcg,thread=multi -cpu max -smp "${MC_VM_SMP:-2}" -m "${MC_VM_MEM:-1024}" \
        -nodefaults -no-user-config -display none -serial stdio -no-reboot \
        -kernel "$dir/vmlinuz" -initrd "$dir/initramfs.cpio.gz" \
        -append "console=ttyS0 quiet loglevel=3 panic=-1 mc_script=$script" \
        -fsdev local,id=hostroot,path=/,security_model=none,multidevs=remap \
        -device virtio-9p-pci,fsdev=hostroot,mount_tag=hostroot \
        </dev/null || true
    [ -r "$script.rc" ] || die "the VM did not report an exit code (boot failed or timed out)"
    rc=$(cat "$script.rc")
    rm -f "$script.rc"
    return "$rc"
}

native() {
    # Try to create a vcan interface on this kernel (needs CAP_NET_ADMIN).
    local name=mcprobe$$
    if ip link add dev "$name" type vcan 2>/dev/null; then
        ip link del dev "$name"
        return 0
    fi
    return 1
}

case "${1:-}" in
    prepare) prepare ;;
    run) [ $# -eq 2 ] || die "usage: $0 run SCRIPT"; run "$2" ;;
    native) native ;;
    *) die "usage: $0 prepare | run SCRIPT | native" ;;
esac
