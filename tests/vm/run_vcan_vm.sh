#!/bin/sh
# Boots a Debian kernel under qemu (TCG) with an initramfs built here, so the
# service runs on a real SocketCAN interface (vcan0) although the host
# kernel has no CAN (DESIGN.md "How the real parts start in tests"). Inside:
# the can, can-raw, can-dev and vcan modules, vcan0 up, a multicast route on
# lo for LCM; canplayer (can-utils) puts can.log on vcan0 while candump
# counts the frames; then loadidd runs live on vcan0 and LCM while
# loadid-replay puts the recording on both; the saved estimate and the
# verdict are printed on the serial console, which this script prints.
#
# Usage: run_vcan_vm.sh WORKDIR LOADIDD LOADID_REPLAY RECORDING_DIR URDF
set -eu
work=$1 loadidd=$2 replay=$3 rec=$4 urdf=$5
mkdir -p "$work"
cd "$work"

# The kernel and its modules: linux-image-amd64 is a metapackage; fetch the
# image it depends on (cached in WORKDIR).
pkg=$(apt-cache depends linux-image-amd64 2>/dev/null | awk '/Depends: linux-image-/{print $2; exit}')
if [ -z "$pkg" ]; then  # no package lists yet (a fresh image)
    apt-get update -q >/dev/null
    pkg=$(apt-cache depends linux-image-amd64 | awk '/Depends: linux-image-/{print $2; exit}')
fi
if [ ! -d "kernel/$pkg" ]; then
    rm -rf kernel dl && mkdir -p kernel dl
    (cd dl && apt-get download "$pkg" >/dev/null 2>&1)
    dpkg-deb -x dl/*.deb "kernel/$pkg"
fi
kdir=kernel/$pkg
kver=$(ls "$kdir/lib/modules")
vmlinuz=$kdir/boot/vmlinuz-$kver
mods=$kdir/lib/modules/$kver/kernel

root=$work/root
rm -rf "$root"
mkdir -p "$root/bin" "$root/lib/modules" "$root/data" "$root/proc" "$root/sys" "$root/dev" \
         "$root/tmp" "$root/results"
cp /bin/busybox "$root/bin/busybox"
for a in sh mount insmod sleep cat echo kill poweroff wc ls grep; do ln -s busybox "$root/bin/$a"; done
for m in net/can/can.ko net/can/can-raw.ko drivers/net/can/dev/can-dev.ko drivers/net/can/vcan.ko; do
    cp "$mods/$m" "$root/lib/modules/"
done

# Programs with their shared libraries (and the dynamic loader).
copy_prog() {
    cp "$1" "$root/bin/"
    ldd "$1" | awk '/=> \//{print $3} /^\t\/lib64/{print $1}' | while read -r lib; do
        mkdir -p "$root$(dirname "$lib")"
        cp -L "$lib" "$root$lib"
    done
}
for p in "$loadidd" "$replay" "$(command -v ip)" "$(command -v canplayer)" "$(command -v candump)"; do
    copy_prog "$p"
done
mkdir -p "$root/lib64"
cp -L /lib64/ld-linux-x86-64.so.2 "$root/lib64/"

cp "$rec/can.log" "$rec/lcm.log" "$root/data/"
cp "$urdf" "$root/data/robot.urdf"
cat > "$root/data/loadid.yaml" <<'YAML'
robot:
  urdf: robot.urdf
can:
  interface: vcan0
lcm:
  url: udpm://239.255.76.67:7667?ttl=0
results:
  directory: /results
kalman:
  max_joint_age_s: 0.02         # TCG emulation delays the LCM stream by ms
YAML

cat > "$root/init" <<'INIT'
#!/bin/sh
mount -t proc proc /proc
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mount -t tmpfs tmp /tmp
for m in can can-raw can-dev vcan; do insmod /lib/modules/$m.ko || echo "LOADID-VERDICT fail insmod $m"; done
ip link set lo up
ip route add 224.0.0.0/4 dev lo
ip link add dev vcan0 type vcan
ip link set vcan0 up
cd /data
# canplayer's syntax: every line of can.log reaches vcan0.
lines=$(wc -l < can.log)
candump -r 4194304 -L vcan0 > /tmp/dump.log &
dumper=$!
sleep 0.5
canplayer -I can.log
sleep 0.5
kill $dumper
echo "LOADID-CANPLAYER lines $lines received $(wc -l < /tmp/dump.log)"
# The service on vcan0 and LCM, fed by loadid-replay.
loadidd --config /data/loadid.yaml --verbose 2> /tmp/loadidd.err &
daemon=$!
sleep 1
loadid-replay --interface vcan0 /data
sleep 2
kill -TERM $daemon
sleep 1
cat /tmp/loadidd.err
echo "LOADID-RESULT-BEGIN"
cat /results/latest.yaml
echo "LOADID-RESULT-END"
echo "LOADID-VERDICT done"
poweroff -f
INIT
chmod +x "$root/init"
(cd "$root" && find . | cpio -o -H newc 2>/dev/null | gzip -1) > "$work/initramfs.gz"

timeout 600 qemu-system-x86_64 -accel tcg -smp 2 -m 512 -nographic -no-reboot \
    -kernel "$vmlinuz" -initrd "$work/initramfs.gz" \
    -append "console=ttyS0 quiet panic=-1" < /dev/null
