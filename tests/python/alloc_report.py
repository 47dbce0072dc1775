"""The report of the allocation counter (tests/support/alloc_count.c,
preloaded into loadidd by test_live_no_alloc.py and, in the VM, by
tests/vm/run_vcan_vm.sh): its counts, and the allocating call sites of the
loop with loadidd's frames resolved."""

from __future__ import annotations

import re
import shutil
import subprocess


def counts(report: str) -> dict:
    """loop_allocations, shutdown_allocations, epoll_waits."""
    return {k: int(v) for k, v in (l.split()[:2] for l in report.splitlines()
                                   if l.strip() and not l.startswith("site"))}


def resolve(site: str, exe: str) -> str:
    """loadidd's frames as function (file:line), by addr2line on EXE (the
    preloaded library's dladdr sees only exported symbols)."""

    def one(m):
        if not shutil.which("addr2line"):
            return m.group(0)
        r = subprocess.run(["addr2line", "-f", "-i", "-s", "-e", exe, m.group(1)],
                           capture_output=True, text=True)
        lines = r.stdout.split()
        return " < ".join(f"{f} ({w})" for f, w in zip(lines[::2], lines[1::2])) or m.group(0)

    return re.sub(r"loadidd\+(0x[0-9a-f]+)\(\?\)", one, site)


def loop_sites(report: str, exe: str) -> list:
    """The call sites that allocated inside the loop, resolved."""
    return [resolve(l, exe) for l in report.splitlines()
            if l.startswith("site") and not l.startswith("site loop 0 ")]
