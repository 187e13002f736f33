"""Interrupts through the occgt binary (apps/interrupt.h, docs/CLI.md "Interrupts"):

1. `occgt inspect split` whose gnuplot ends by SIGINT (Ctrl-C reaches the whole process
   group; occgt ignores SIGINT while std::system waits): the one line of the shared handler
   (it was "occgt: interrupted (gnuplot ended by SIGINT)" before inspect split installed
   it), the process ends by SIGINT (exit status 130 in a shell) and no report folder is
   left. It was `occgt: error: gnuplot: failed on the generated plots.gp script`, exit 1.
   gnuplot crashing (SIGSEGV) names the signal, exit 1, not the script either.
2. `occgt inspect split` itself interrupted (not its gnuplot): SIGINT or SIGTERM while it
   publishes the report's files (held there by a FIFO at report.html.tmp), SIGTERM while
   gnuplot runs (std::system ignores SIGINT meanwhile): the one line of the shared handler,
   the end by the signal, no temporary left (`*.tmp`, the `.plots.tmp/` scratch folder) and
   no report folder it created. It ended silently, leaving them.
3. `occgt synth` interrupted with SIGINT and SIGTERM: the one line of the shared handler (it
   printed nothing) and the end by the signal.
(build: build_lock_test.py; render: render_test.py.)"""
import os
import signal
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import common  # noqa: E402


INSPECT_LINE = ("occgt: interrupted; the report folder may hold some files of this run beside an "
                "earlier run's: re-run the same command")


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
            (signal.SIGINT, -signal.SIGINT, INSPECT_LINE),
            (signal.SIGTERM, -signal.SIGTERM, INSPECT_LINE),
            (signal.SIGSEGV, 1, "occgt: error: gnuplot: 'gnuplot' was killed by signal 11 "
                                "(Segmentation fault)")):
        env = dict(os.environ, PATH=fake_gnuplot(tmp, sig) + ":" + os.environ["PATH"])
        out = os.path.join(tmp, f"report{sig}")
        r = common.occgt("inspect", "split", split, "--out", out, check=False, env=env)
        assert r.returncode == rc, (sig, r.returncode, r.stderr)
        assert [x for x in r.stderr.splitlines() if x] == [line], (sig, r.stderr)
        assert not os.path.exists(out), f"report folder left after gnuplot's {sig}"


REPORT_PLOTS = ["overlap_hist.png", "occlusion_hist.png", "occlusion_cumulative.png",
                "overlap_vs_occlusion.png", "pairs_per_scene.png"]


def interrupt_inspect(split, out, sig, ready, env=None):
    """Runs `occgt inspect split` into out, waits until ready() (the run is at the point to
    interrupt), sends sig to occgt alone (not its process group: not to gnuplot) and returns
    (returncode, the non-empty stderr lines). stderr goes to a file: a gnuplot still running
    after occgt ended would hold a pipe open."""
    err_path = out + ".stderr"
    with open(err_path, "w") as err_file:
        p = subprocess.Popen([common.BINARY, "inspect", "split", split, "--out", out],
                             stdout=subprocess.DEVNULL, stderr=err_file, env=env,
                             start_new_session=True)
    try:
        deadline = time.time() + 60
        while p.poll() is None and time.time() < deadline and not ready():
            time.sleep(0.01)
        assert p.poll() is None, f"inspect split ended before it could be interrupted: {open(err_path).read()}"
        assert ready(), "inspect split did not reach the point to interrupt within 60 s"
        os.kill(p.pid, sig)
        p.wait(timeout=60)
    finally:
        if p.poll() is None:  # still running: end it, then fail
            p.kill()
            p.wait()
    with open(err_path) as f:
        return p.returncode, [x for x in f.read().splitlines() if x]


def test_inspect_interrupted():
    tmp = common.scratch("interrupt_inspect_itself")
    split = os.path.join(tmp, "split")
    os.makedirs(split)
    open(os.path.join(split, "pairs.jsonl"), "w").close()
    # While it publishes: the plots are at their names and report.html.tmp, a FIFO, holds the
    # open(2) of its temporary until a reader comes (none does).
    for sig in (signal.SIGINT, signal.SIGTERM):
        out = os.path.join(tmp, f"writing{sig}")
        os.makedirs(out)
        os.mkfifo(os.path.join(out, "report.html.tmp"))
        rc, err = interrupt_inspect(
            split, out, sig,
            lambda: all(os.path.exists(os.path.join(out, n)) for n in REPORT_PLOTS))
        assert rc == -sig, (sig, rc, err)
        assert err == [INSPECT_LINE], (sig, err)
        left = sorted(os.listdir(out))
        assert not [n for n in left if n.endswith(".tmp")], f"temporaries left after {sig}: {left}"
        # What is at a final name is whole: this run's plots (each published atomically),
        # beside the report folder's lock file (empty; kept, as the folder was there before).
        assert left == sorted(REPORT_PLOTS + [".inspect.lock"]), (sig, left)
        assert os.path.getsize(os.path.join(out, ".inspect.lock")) == 0
        for name in REPORT_PLOTS:
            with open(os.path.join(out, name), "rb") as f:
                assert f.read().endswith(b"IEND\xaeB`\x82"), f"{name}: not a whole PNG"
    # While gnuplot runs (a gnuplot that waits): occgt alone gets SIGTERM. The scratch folder
    # OUT/.plots.tmp/ and the report folder this run created are removed.
    bin_dir = os.path.join(tmp, "bin_slow")
    os.makedirs(bin_dir)
    pid_file = os.path.join(tmp, "gnuplot.pid")
    with open(os.path.join(bin_dir, "gnuplot"), "w") as f:
        f.write(f"#!/bin/sh\necho $$ > {pid_file}.part && mv {pid_file}.part {pid_file}\n"
                "exec sleep 60\n")
    os.chmod(os.path.join(bin_dir, "gnuplot"), 0o755)
    env = dict(os.environ, PATH=bin_dir + ":" + os.environ["PATH"])
    out = os.path.join(tmp, "plotting")
    try:
        rc, err = interrupt_inspect(split, out, signal.SIGTERM, lambda: os.path.exists(pid_file),
                                    env=env)
    finally:
        if os.path.exists(pid_file):
            try:
                os.kill(int(open(pid_file).read()), signal.SIGKILL)
            except ProcessLookupError:
                pass
    assert rc == -signal.SIGTERM, (rc, err)
    assert err == [INSPECT_LINE], err
    assert not os.path.exists(out), f"report folder left: {os.listdir(out)}"


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
    test_inspect_interrupted()
    test_synth_interrupted()
    print("interrupt: inspect's gnuplot ended by SIGINT/SIGTERM is an interrupt, SIGSEGV named; "
          "inspect split interrupted itself and synth print the shared line, inspect leaves no "
          "temporary")
