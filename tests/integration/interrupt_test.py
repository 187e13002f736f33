"""Interrupts through the occgt binary (apps/interrupt.h, docs/CLI.md "Interrupts"):
`occgt synth` interrupted with SIGINT and SIGTERM: the one line of the shared handler (it
printed nothing) and the end by the signal.
(build: build_lock_test.py; render: render_test.py.)"""
import os
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402


def test_synth_interrupted():
    tmp = common.scratch("interrupt_synth")
    for sig in (signal.SIGINT, signal.SIGTERM):
        out = os.path.join(tmp, f"synth{sig}")
        p = subprocess.Popen([common.BINARY, "synth", "--out", out, "--scenes", "4", "--frames",
                              "400"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True,
                             start_new_session=True)
        deadline = time.time() + 60
        while p.poll() is None and time.time() < deadline and not os.path.exists(out):
            time.sleep(0.01)
        time.sleep(0.2)
        assert p.poll() is None, "synth ended before it could be interrupted"
        os.killpg(p.pid, sig)
        _, err = p.communicate(timeout=60)
        assert p.returncode == -sig, (sig, p.returncode, err)
        assert [x for x in err.splitlines() if x] == [
            "occgt: interrupted; the dataset in --out is incomplete: re-run the same command"], err


if __name__ == "__main__":
    test_synth_interrupted()
    print("interrupt: synth prints the shared line")
