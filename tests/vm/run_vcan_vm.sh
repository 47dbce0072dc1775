#!/bin/sh
# Boots a Debian kernel under qemu (TCG) with an initramfs built here, so the
# service runs on a real SocketCAN interface (vcan0) although the host
# kernel has no CAN (docs/ARCHITECTURE.md). Inside:
# the can, can-raw, can-dev and vcan modules, vcan0 up, a multicast route on
# lo for LCM; canplayer (can-utils) puts can.log on vcan0 while candump
# counts the frames; then loadidd runs live on vcan0 and LCM while
# loadid-replay puts the recording on both, with the allocation counter
# (tests/support/alloc_count.c) preloaded, estimate_watch printing its final
# estimates and loadid-record beside it recording what it receives (sent
# back as a base64 tar, for `loadidd --offline` on the host). Then fault
# injection: loadidd
# live on the hand-made parts in FAULTS_DIR (tests/vm/fault_session.py),
# `loadid zero`, `start` and `stop` between them, one part beside CAN_FLOOD's
# foreign frames at the full bus rate; a second run with vcan0 removed and
# added again inside it; `loadid status` and estimate_watch read back what
# the daemon counted and estimated. Then a daemon stopped (SIGSTOP) while
# more frames come than its socket holds: the kernel's drop count. Last,
# loadidd's refusal of a bad configuration and of a missing interface.
# Everything is printed on the serial console between LOADID-* markers;
# this script prints the console and test_vcan_vm.py judges it.
#
# Timing: the test replays recordings in real time, and an emulated CPU
# that the host's load starves falls behind them: the JR3 frames then carry
# the (late) time they went out, the joint states the time they were due,
# and the estimate is wrong (seen on this 2-core machine under load: 8 %
# of the mass live, 44 % from the recorded session). So the VM runs with
# -icount shift=0,sleep=off: its clocks advance by the instructions it
# executes (1 ns each) and jump ahead when it idles, so its real time is
# its own, whatever the host's load; a loaded host makes the run longer
# in wall time, not the VM late. icount hangs the kernel bringing up a
# second CPU (QEMU 7.2), and runs the CPUs of a VM one at a time anyway,
# so the VM has one. Waits in the VM are in its own time; where a condition
# can be waited for (the daemon's first status_t, the saved estimate, the
# recorder's start), it is, with a deadline. The host side measures the
# boot in wall time (from LOADID-QEMU-START to /init's LOADID-BOOT line)
# and gives the rest of the run a deadline in boots (test_vcan_vm.py).
#
# Usage: run_vcan_vm.sh WORKDIR LOADIDD LOADID_REPLAY RECORDING_DIR URDF
#                       LOADID_CLI LOADID_RECORD ESTIMATE_WATCH FAULTS_DIR CAN_FLOOD
#                       ALLOC_COUNT_LIB
set -eu
work=$1 loadidd=$2 replay=$3 rec=$4 urdf=$5 cli=$6 record=$7 watch=$8 faults=$9 flood=${10}
alloc=${11}
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
for a in sh mount insmod sleep cat echo kill poweroff wc ls grep tar gzip base64 taskset; do ln -s busybox "$root/bin/$a"; done
for m in net/can/can.ko net/can/can-raw.ko drivers/net/can/dev/can-dev.ko drivers/net/can/vcan.ko; do
    cp "$mods/$m" "$root/lib/modules/"
done

# Programs (to PATH in the VM, default /bin/NAME) with their shared
# libraries (and the dynamic loader), without debug information (a
# debuginfo build's is most of their size, and the initramfs must unpack in
# the VM's 512 MB).
copy_prog() {
    strip --strip-debug -o "$root${2:-/bin/$(basename "$1")}" "$1"
    ldd "$1" | awk '/=> \//{print $3} /^\t\/lib64/{print $1}' | while read -r lib; do
        mkdir -p "$root$(dirname "$lib")"
        cp -L "$lib" "$root$lib"
    done
}
for p in "$loadidd" "$replay" "$cli" "$record" "$watch" "$flood" "$(command -v ip)" "$(command -v canplayer)" "$(command -v candump)"; do
    copy_prog "$p"
done
# The allocation counter, preloaded into the first daemon (its backtrace()
# loads libgcc_s, which loadidd links already).
copy_prog "$alloc" /lib/liballoc_count.so
mkdir -p "$root/lib64"
cp -L /lib64/ld-linux-x86-64.so.2 "$root/lib64/"

cp "$rec/can.log" "$rec/lcm.log" "$root/data/"
cp "$urdf" "$root/data/robot.urdf"
mkdir -p "$root/data/faults"
cp -r "$faults"/* "$root/data/faults/"
printf 'robot: [not, a, mapping]\n' > "$root/data/bad.yaml"
printf 'robot:\n  urdf: robot.urdf\ncan:\n  interface: nosuch0\n' > "$root/data/nosuch.yaml"
cat > "$root/data/loadid.yaml" <<'YAML'
robot:
  urdf: robot.urdf
can:
  interface: vcan0
lcm:
  url: udpm://239.255.76.67:7667?ttl=0
estimation:
  methods: [RTLS, RIV, RLS, REFINED]  # REFINED: the worker thread in the counted loop
results:
  directory: /results
kalman:
  max_joint_age_s: 0.02         # TCG emulation delays the LCM stream by ms
YAML

cat > "$root/init" <<'INIT'
#!/bin/sh
mount -t proc proc /proc
# The kernel's uptime [1/100 s] (/proc/uptime has two decimals): the VM's
# own time under -icount.
now_cs() {
    read up idle < /proc/uptime
    frac=${up#*.}
    echo $(( ${up%.*} * 100 + ${frac#0} ))
}
echo "LOADID-BOOT uptime_cs $(now_cs)"
# within MS COMMAND...: runs COMMAND every 0.1 s until it succeeds, for at
# most MS milliseconds; fails when it never did.
within() {
    end=$(( $(now_cs) + $1 / 10 ))
    shift
    until "$@"; do
        [ "$(now_cs)" -lt "$end" ] || return 1
        sleep 0.1
    done
}
# The daemon is up when its loop has published a status_t.
daemon_up() { loadid --config "$1" status --timeout 3 > /dev/null; }
mount -t sysfs sys /sys
mount -t devtmpfs dev /dev
mount -t tmpfs tmp /tmp
for m in can can-raw can-dev vcan; do insmod /lib/modules/$m.ko || echo "LOADID-VERDICT fail insmod $m"; done
ip link set lo up
ip route add 224.0.0.0/4 dev lo
ip link add dev vcan0 type vcan
ip link set vcan0 up
cd /data
# Senders stay on one CPU: vcan and lo hand each frame or datagram to the
# backlog of the CPU that sent it, so a sender migrating between two CPUs
# reorders what every socket receives (seen: whole JR3 samples and joint
# states out of order, counted as gaps and bad messages). With one CPU
# (-icount) there is nothing to pin.
pin=
[ "$(grep -c ^processor /proc/cpuinfo)" -eq 1 ] || pin="taskset 0x2"
# canplayer's syntax: every line of can.log reaches vcan0.
lines=$(wc -l < can.log)
candump -r 4194304 -L vcan0 > /tmp/dump.log &
dumper=$!
sleep 0.5
$pin canplayer -I can.log
# candump has written every line, or stopped getting more.
dumped() { [ "$(wc -l < /tmp/dump.log)" -ge "$lines" ]; }
within 5000 dumped || true
kill $dumper
echo "LOADID-CANPLAYER lines $lines received $(wc -l < /tmp/dump.log)"
# The service on vcan0 and LCM, fed by loadid-replay, with the allocation
# counter preloaded: it counts every allocation between the daemon's first
# epoll_wait and its last (the report at exit). Beside it estimate_watch
# prints the final estimates and loadid-record records the frames and joint
# states the daemon receives (both sockets get every frame with the same
# kernel time stamp), for `loadidd --offline` on the host.
estimate_watch > /tmp/live_estimates.txt &
watcher=$!
loadid-record --config /data/loadid.yaml --out /tmp/recorded 2> /tmp/record.err &
recorder=$!
LD_PRELOAD=/lib/liballoc_count.so LOADID_ALLOC_REPORT=/tmp/alloc.txt \
    loadidd --config /data/loadid.yaml --verbose 2> /tmp/loadidd.err &
daemon=$!
within 10000 daemon_up /data/loadid.yaml || echo "LOADID-VERDICT fail loadidd not up"
within 5000 grep -q recording /tmp/record.err || echo "LOADID-VERDICT fail loadid-record not up"
$pin loadid-replay --interface vcan0 /data
# DONE: the estimate saved (after REFINED); then the replay's last samples
# counted.
within 10000 [ -e /results/latest.yaml ] || echo "LOADID-VERDICT fail no saved estimate"
sleep 0.5
kill -TERM $daemon
wait $daemon && echo "LOADID-LIVE-EXIT 0" || echo "LOADID-LIVE-EXIT $?"
kill -TERM $recorder
wait $recorder && echo "LOADID-RECORD-EXIT 0" || echo "LOADID-RECORD-EXIT $?"
kill -TERM $watcher
wait $watcher || true
cat /tmp/loadidd.err /tmp/record.err
echo "LOADID-LIVE-ESTIMATES-BEGIN"
cat /tmp/live_estimates.txt
echo "LOADID-LIVE-ESTIMATES-END"
echo "LOADID-ALLOC-BEGIN"
cat /tmp/alloc.txt
echo "LOADID-ALLOC-END"
echo "LOADID-RESULT-BEGIN"
cat /results/latest.yaml
echo "LOADID-RESULT-END"
echo "LOADID-RECORDING-BEGIN"
tar -C /tmp -cf - recorded | gzip -1 | base64
echo "LOADID-RECORDING-END"

# Fault injection: the hand-made parts of tests/vm/fault_session.py, with
# the CLI's commands between them (each after the daemon has read the part
# before). `loadid status` prints the daemon's next status_t (1 Hz).
cd /data/faults
status_block() {
    echo "LOADID-$1-BEGIN"
    loadid --config faults.yaml status --timeout 3 || echo "LOADID-VERDICT fail loadid status ($1)"
    echo "LOADID-$1-END"
}
loadidd --config faults.yaml --verbose 2> /tmp/faults.err &
daemon=$!
estimate_watch > /tmp/estimates.txt &
watcher=$!
within 10000 daemon_up faults.yaml || echo "LOADID-VERDICT fail loadidd not up (faults)"
sleep 0.5  # estimate_watch subscribed
for step in "idle zero" "zeroing start" "window -"; do
    set -- $step
    $pin loadid-replay --interface vcan0 $1
    sleep 0.3
    [ "$2" = - ] || loadid --config faults.yaml $2 --load-name faults
done
# Still estimating: `quiet`, then the same samples beside can_flood's
# foreign frames at the full bus rate (flood.args: rate, seconds); the loop
# times of two seconds inside each, and the counts after each.
for part in quiet flood; do
    flooder=
    if [ $part = flood ]; then
        can_flood vcan0 $(cat flood.args) > /tmp/flood.txt &
        flooder=$!
    fi
    $pin loadid-replay --interface vcan0 $part &
    replayer=$!
    sleep 1.2
    status_block LOOP-$part-1
    status_block LOOP-$part-2
    wait $replayer
    [ -z "$flooder" ] || wait $flooder
    sleep 0.3
    status_block COUNTS-$part
done
cat /tmp/flood.txt
loadid --config faults.yaml stop --load-name faults
$pin loadid-replay --interface vcan0 done
sleep 0.3
status_block STATUS
# A second run with vcan0 removed under it and added again a second later,
# while the outage part's samples keep coming (loadid-replay keeps its
# schedule and counts the frames it could not send).
loadid --config faults.yaml start --load-name outage
$pin loadid-replay --interface vcan0 outage 2> /tmp/outage.err &
replayer=$!
sleep 1
gone=$(now_cs)
ip link del dev vcan0
sleep 1
ip link add dev vcan0 type vcan && ip link set vcan0 up
echo "LOADID-OUTAGE gone_cs $(( $(now_cs) - gone ))"
wait $replayer
sleep 0.3
loadid --config faults.yaml stop --load-name outage
status_block STATUS2
cat /tmp/outage.err
# loadid-record --duration, every channel: the daemon's status_t (once a
# second), nothing on vcan0.
loadid-record --all-channels --duration 1.5 --out /tmp/short 2> /tmp/short.err && \
    echo "LOADID-SHORT-EXIT 0" || echo "LOADID-SHORT-EXIT $?"
kill -0 $daemon && echo "LOADID-FAULTS-ALIVE"
kill -TERM $daemon
wait $daemon && echo "LOADID-FAULTS-EXIT 0" || echo "LOADID-FAULTS-EXIT $?"
kill -TERM $watcher
wait $watcher || true
echo "LOADID-FAULTS-BEGIN"
cat /tmp/estimates.txt /tmp/faults.err
echo "LOADID-FAULTS-END"
cat /tmp/short.err

# The socket's receive buffer overflowed: a daemon of its own, stopped
# (SIGSTOP) while the burst part sends more frames than the buffer holds;
# the post part's first frame brings the kernel's drop count.
loadidd --config faults.yaml --verbose 2> /tmp/overflow.err &
daemon=$!
within 10000 daemon_up faults.yaml || echo "LOADID-VERDICT fail loadidd not up (overflow)"
$pin loadid-replay --interface vcan0 pre
sleep 0.3
kill -STOP $daemon
$pin loadid-replay --interface vcan0 burst
kill -CONT $daemon
sleep 0.5  # the buffer read: the post part's frames all fit
$pin loadid-replay --interface vcan0 post
sleep 0.3
status_block OVERFLOW-STATUS
kill -TERM $daemon
wait $daemon && echo "LOADID-OVERFLOW-EXIT 0" || echo "LOADID-OVERFLOW-EXIT $?"
echo "LOADID-OVERFLOW-BEGIN"
cat /tmp/overflow.err
echo "LOADID-OVERFLOW-END"
cd /data

# Refusals in live mode: one line on stderr, a non-zero exit.
for c in bad nosuch; do
    loadidd --config /data/$c.yaml 2> /tmp/$c.err && s=0 || s=$?
    echo "LOADID-REFUSAL $c exit $s lines $(wc -l < /tmp/$c.err): $(cat /tmp/$c.err)"
done
echo "LOADID-END uptime_cs $(now_cs)"
echo "LOADID-VERDICT done"
poweroff -f
INIT
chmod +x "$root/init"
(cd "$root" && find . | cpio -o -H newc 2>/dev/null | gzip -1) > "$work/initramfs.gz"

echo "LOADID-QEMU-START"
exec qemu-system-x86_64 -accel tcg -icount shift=0,sleep=off -smp 1 -m 512 -nographic -no-reboot \
    -kernel "$vmlinuz" -initrd "$work/initramfs.gz" \
    -append "console=ttyS0 quiet panic=-1" < /dev/null
