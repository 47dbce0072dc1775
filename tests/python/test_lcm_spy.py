"""lcm-spy decodes the project's LCM types (docs/INTERFACE.md): tools/spy/loadid-spy
starts lcm.spy.Spy with Debian's lcm.jar, jchart2d and the build's
loadid_lcmtypes.jar under Xvfb, in a private network namespace, while
estimate_t messages are published; it must report the project's 6 types,
lcm-spy's type database (SpyDecodeCheck.java) must decode a live
estimate_t to what was sent, and a screenshot of its channel table is saved as a test artefact
(LOADID_ARTIFACT_DIR, default the build's tests/artifacts)."""

from __future__ import annotations

import os
import pathlib
import shutil
import subprocess
import sys

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]

SESSION = r'''
set -eu
ip link set lo up
ip route add 224.0.0.0/4 dev lo
Xvfb :77 -screen 0 1024x700x24 >/dev/null 2>&1 &
xvfb=$!
sleep 1
DISPLAY=:77 "$SPY" --jar "$JAR" > "$OUT/spy.out" 2>&1 &
spy=$!
java -cp "/usr/share/java/lcm.jar:$JAR" "$CHECK" "udpm://239.255.76.67:7667?ttl=0" \
    > "$OUT/decode.out" 2>&1 &
check=$!
"$PYTHON" - <<'PY'
import os, sys, time, lcm
sys.path.insert(0, os.environ["LOADID_LCM_PYTHON_DIR"])
import loadid
lc = lcm.LCM("udpm://239.255.76.67:7667?ttl=0")
m = loadid.estimate_t()
m.method, m.state, m.load_name, m.mass = 3, 2, "o1", 1.0
for i in range(80):
    m.utime, m.samples = int(time.time() * 1e6), i
    lc.publish("LOADID_ESTIMATE", m.encode())
    time.sleep(0.05)
PY
DISPLAY=:77 import -window root "$OUT/lcm-spy.png"
wait $check || echo "decode check exited $?" >> "$OUT/decode.out"
kill $spy $xvfb
'''


def test_lcm_spy_decodes_estimate_t(tmp_path):
    for tool in ("Xvfb", "import", "java", "unshare", "ip"):
        if not shutil.which(tool):
            pytest.fail(f"{tool} is missing: tools/setup.sh installs it")
    jar = os.environ.get("LOADID_LCMTYPES_JAR", "")
    assert os.path.isfile(jar), "LOADID_LCMTYPES_JAR must name the built jar (ctest sets it)"
    out = pathlib.Path(os.environ.get("LOADID_ARTIFACT_DIR", tmp_path))
    out.mkdir(parents=True, exist_ok=True)
    env = dict(os.environ, SPY=str(REPO / "tools" / "spy" / "loadid-spy"), JAR=jar,
               OUT=str(out), PYTHON=sys.executable,
               CHECK=str(REPO / "tests" / "python" / "SpyDecodeCheck.java"))
    r = subprocess.run(["unshare", "-n", "sh", "-c", SESSION], env=env, capture_output=True,
                       text=True, timeout=120)
    spy_out = (out / "spy.out").read_text() if (out / "spy.out").exists() else ""
    # A spy that exited early (a headless Java: HeadlessException) makes
    # the final kill fail; its own output says why.
    assert r.returncode == 0, r.stderr + "\nlcm-spy's output:\n" + spy_out
    assert "Found 6 LCM types" in spy_out, spy_out
    # lcm-spy's own type lookup (LCMTypeDatabase, the same class path)
    # decoded the live message to what was sent.
    decoded = (out / "decode.out").read_text()
    assert "loadid.estimate_t method=3 state=2 load_name=o1 mass=1.0" in decoded, decoded
    shot = out / "lcm-spy.png"
    assert shot.stat().st_size > 1000
    # The screenshot is an image of the screen's size (identify, ImageMagick).
    ident = subprocess.run(["identify", str(shot)], capture_output=True, text=True, check=True)
    assert "1024x700" in ident.stdout
