"""Interrupts through the occgt binary (apps/interrupt.h, docs/CLI.md "Interrupts"):

1. `occgt inspect split` whose gnuplot ends by SIGINT (Ctrl-C reaches the whole process
   group; occgt ignores SIGINT while std::system waits): "occgt: interrupted (gnuplot ended
   by SIGINT)", the process ends by SIGINT (exit status 130 in a shell) and no report folder
   is left. It was `occgt: error: gnuplot: failed on the generated plots.gp script`, exit 1.
   gnuplot crashing (SIGSEGV) names the signal, exit 1, not the script either.
2. `occgt synth` interrupted with SIGINT and SIGTERM: the one line of the shared handler (it
   printed nothing) and the end by the signal.
(build: build_lock_test.py; render: render_test.py.)"""
import os
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402


def fake_gnuplot(folder, signal_number):
    """A folder holding a `gnuplot` that ends by signal_number."""
    bin_dir = os.path.join(folder, f"bin{signal_number}")
    os.makedirs(bin_dir)
    path = os.path.join(bin_dir, "gnuplot")
    with open(path, "w") as f:
        f.write(f"#!/bin/sh\nkill -{signal_number} $$\n")
    os.chmod(path, 0o755)
    return bin_dir


def test_inspect_gnuplot_signal():
    tmp = common.scratch("interrupt_inspect")
    split = os.path.join(tmp, "split")
    os.makedirs(split)
    open(os.path.join(split, "pairs.jsonl"), "w").close()
    for sig, rc, line in (
            (signal.SIGINT, -signal.SIGINT, "occgt: interrupted (gnuplot ended by SIGINT)"),
            (signal.SIGTERM, -signal.SIGTERM, "occgt: interrupted (gnuplot ended by SIGTERM)"),
            (signal.SIGSEGV, 1, "occgt: error: gnuplot: 'gnuplot' was killed by signal 11 "
                                "(Segmentation fault)")):
        env = dict(os.environ, PATH=fake_gnuplot(tmp, sig) + ":" + os.environ["PATH"])
        out = os.path.join(tmp, f"report{sig}")
        r = common.occgt("inspect", "split", split, "--out", out, check=False, env=env)
        assert r.returncode == rc, (sig, r.returncode, r.stderr)
        assert r.stderr.splitlines() == [line], (sig, r.stderr)
        assert not os.path.exists(out), f"report folder left after gnuplot's {sig}"


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
    test_inspect_gnuplot_signal()
    test_synth_interrupted()
    print("interrupt: inspect's gnuplot ended by SIGINT/SIGTERM is an interrupt, SIGSEGV named; "
          "synth prints the shared line")
