#!/bin/busybox sh
# /init of the CAN test VM's initramfs (busybox, static). Loads the kernel
# modules listed in /modules.order (9p over virtio, then CAN and vcan), mounts
# the host's root file system (shared over 9p) on /host, then runs the script
# named on the kernel command line (mc_script=PATH, a host path) chrooted into
# the host root, writes its exit code to PATH.rc and powers off.
/bin/busybox --install -s /bin
export PATH=/bin
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev 2>/dev/null

die() { echo "mc-vm: $*"; poweroff -f; }

while read -r m; do
    insmod "/modules/$m.ko" || die "insmod $m failed"
done < /modules.order

mkdir -p /host
mount -t 9p -o trans=virtio,version=9p2000.L,msize=262144,cache=loose hostroot /host || die "9p mount failed"
for d in proc sys dev; do mount -o bind "/$d" "/host/$d" || die "bind /$d failed"; done
mount -t tmpfs tmp /host/dev/shm 2>/dev/null

script=""
for arg in $(cat /proc/cmdline); do
    case "$arg" in mc_script=*) script="${arg#mc_script=}" ;; esac
done
[ -n "$script" ] || die "no mc_script= on the kernel command line"
echo "mc-vm: kernel $(uname -r), CAN modules loaded; running $script"
chroot /host /usr/bin/env -i PATH=/usr/local/sbin:/usr/local/bin:/usr/sbin:/usr/bin:/sbin:/bin \
    HOME=/root LANG=C.UTF-8 /bin/sh "$script"
echo "$?" > "/host$script.rc"
sync
poweroff -f
