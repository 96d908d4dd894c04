#!/usr/bin/env python3
"""Fault injection for the flowire command line: full disks, concurrent runs and signals.

usage: fault_injection.py CASE --flowire BIN --preload fail_write.so --examples DIR --work DIR
                          [--seed S] [--budget N] [--trials N]

CASE is one of
  write_failure_run              a short scene, a write into the output folder failing (ENOSPC, and
                                 every later one too: a full disk) at a spread of points of the run
  write_failure_convert_compare  the same for `flowire network convert` and `flowire compare --out`
  concurrent_runs                a second `flowire run` on a folder that a first run holds
  signals                        SIGINT, SIGTERM and SIGKILL at seeded random times of a run, each
                                 followed by a rerun on the same folder

Writes fail (or are slowed down) through the LD_PRELOAD library tests/support/fail_write.c
(FLOWIRE_FAIL_DIR, FLOWIRE_FAIL_AT, FLOWIRE_FAIL_OPS, FLOWIRE_FAIL_COUNT, FLOWIRE_FAIL_TRACE,
FLOWIRE_FAIL_DELAY_US). What is checked is docs/cli.md's promise that a failed or interrupted
run leaves no half-written file:

  every write     an undisturbed run writes each file to a temporary `.<name>.<pid>.<hex>.partial`
                  of its own, used once, and fsyncs it (seen through the library's trace)

  write failure   exit status 2; one stderr line `flowire: error: ...` naming the file whose
                  write failed; no `*.partial` file anywhere in the folder; every output file
                  there is byte-identical to the same file of an undisturbed run (summary.json,
                  which holds timings, is instead valid JSON whose status is not "ok"); an output
                  of convert/compare is absent (or, if it existed before, unchanged).
  folder lock     while a run holds its folder (summary.json says "running" with its pid), a
                  second run exits 2 with a message naming "another flowire run" and the
                  holder's pid and writes nothing into the folder; the first ends "ok".
  signals         SIGINT: exit 130 or death by the signal; SIGTERM: 143 or death by it; then no
                  `*.partial` file and summary.json says "interrupted" or "running". SIGKILL:
                  summary.json is not "ok". Every output file left is complete; a rerun on the
                  folder removes the temporaries of dead processes and ends "ok".

One line `FAIL [case] ...` per failed check; the exit status is 1 if any check failed.
"""
import argparse
import json
import os
import random
import re
import shutil
import signal
import subprocess
import sys
import time

LOCK = ".flowire-run.lock"
TEMP_NAME = re.compile(r"^\.(.+)\.(\d+)\.([0-9a-f]+)\.partial$")
FRAME_NAME = re.compile(r"^.+_\d+\.vtp$")
# Files of two undisturbed runs that may differ, and why.
NOT_REPRODUCIBLE = {"summary.json": "holds the run's timings (seconds per phase)"}


class Checks:
    def __init__(self, case):
        self.case = case
        self.total = 0
        self.failed = 0

    def check(self, ok, what):
        self.total += 1
        if not ok:
            self.failed += 1
            print(f"FAIL [{self.case}] {what}", flush=True)
        return ok

    def fail(self, what):
        return self.check(False, what)

    def note(self, what):
        print(f"note [{self.case}] {what}", flush=True)


class Tool:
    """The flowire program, run with or without the write-failing library."""

    def __init__(self, args):
        self.flowire = os.path.abspath(args.flowire)
        self.preload = os.path.abspath(args.preload)
        self.examples = os.path.abspath(args.examples)

    def env(self, fail=None):
        env = dict(os.environ)
        env.pop("LD_PRELOAD", None)
        for k in list(env):
            if k.startswith("FLOWIRE_FAIL_"):
                del env[k]
        if fail is not None:
            env["LD_PRELOAD"] = self.preload
            # A sanitized flowire wants its runtime first in the library list.
            opts = env.get("ASAN_OPTIONS", "")
            if "verify_asan_link_order" not in opts:
                env["ASAN_OPTIONS"] = (opts + ":" if opts else "") + "verify_asan_link_order=0"
            for k, v in fail.items():
                env["FLOWIRE_FAIL_" + k.upper()] = str(v)
        return env

    def popen(self, argv, fail=None, stdout=subprocess.PIPE, stderr=subprocess.PIPE):
        return subprocess.Popen([self.flowire] + argv, env=self.env(fail), stdout=stdout, stderr=stderr,
                                stdin=subprocess.DEVNULL, text=True, preexec_fn=default_signals)

    def run(self, argv, fail=None, timeout=120):
        p = self.popen(argv, fail)
        try:
            out, err = p.communicate(timeout=timeout)
            return Result(p.returncode, out, err, False, p.pid)
        except subprocess.TimeoutExpired:
            p.kill()
            out, err = p.communicate()
            return Result(p.returncode, out, err, True, p.pid)


class Result:
    def __init__(self, rc, out, err, timed_out, pid):
        self.rc, self.out, self.err, self.timed_out, self.pid = rc, out, err, timed_out, pid


def default_signals():
    # The child starts with SIGINT and SIGTERM at their defaults, whatever the test runner set.
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)


# ---------------------------------------------------------------- folders and files


def fresh(path):
    shutil.rmtree(path, ignore_errors=True)
    os.makedirs(path)
    return os.path.realpath(path)


def all_files(folder):
    """Relative paths of every file under `folder` (hidden ones too)."""
    found = []
    for root, _, names in os.walk(folder):
        for n in names:
            found.append(os.path.relpath(os.path.join(root, n), folder))
    return sorted(found)


def is_partial(rel):
    name = os.path.basename(rel)
    return name.endswith(".partial") or ".partial." in name


def partial_files(folder):
    return [f for f in all_files(folder) if is_partial(f)]


def output_files(folder):
    """The files a user sees: not hidden, not temporaries."""
    return [f for f in all_files(folder) if not os.path.basename(f).startswith(".") and not is_partial(f)]


def stray_hidden_files(folder):
    """Hidden files other than the run lock and the temporaries (reported on their own)."""
    return [f for f in all_files(folder)
            if os.path.basename(f).startswith(".") and os.path.basename(f) != LOCK and not is_partial(f)]


def read_bytes(path):
    with open(path, "rb") as f:
        return f.read()


def target_name(path):
    """The output file a temporary (or the file itself) stands for."""
    if path.endswith(" (deleted)"):
        path = path[: -len(" (deleted)")]
    name = os.path.basename(path)
    m = TEMP_NAME.match(name)
    if m:
        return m.group(1)
    if name.endswith(".partial"):
        return name[: -len(".partial")]
    if ".partial." in name:
        return name[: name.index(".partial.")]
    return name


def read_summary(folder):
    """(status, the summary dict or None, problem or None)."""
    path = os.path.join(folder, "summary.json")
    if not os.path.exists(path):
        return None, None, None
    try:
        with open(path) as f:
            s = json.load(f)
    except (OSError, ValueError) as e:
        return None, None, f"summary.json is not valid JSON (cut off?): {e}"
    if not isinstance(s, dict):
        return None, None, "summary.json is not a JSON object"
    return s.get("status"), s, None


def incomplete(path):
    """Why the file at `path` is not a complete output of its kind (None if it is)."""
    data = read_bytes(path)
    name = os.path.basename(path)
    if not data:
        return "is empty"
    if name.endswith((".vtp", ".pvd", ".vtu")):
        if not data.rstrip().endswith(b"</VTKFile>"):
            return "does not end with </VTKFile> (cut off)"
    elif name.endswith(".csv"):
        if not data.endswith(b"\n"):
            return "does not end with a newline (cut off)"
        lines = data.decode("utf-8", "replace").splitlines()
        if '"' not in data.decode("utf-8", "replace"):
            n = lines[0].count(",")
            bad = [i + 1 for i, line in enumerate(lines) if line.count(",") != n]
            if bad:
                return f"line {bad[0]} has {lines[bad[0] - 1].count(',') + 1} fields, the header {n + 1} (cut off)"
    elif name.endswith(".json"):
        try:
            json.loads(data)
        except ValueError as e:
            return f"is not valid JSON: {e}"
    elif name.endswith(".py"):
        try:
            compile(data, path, "exec")
        except SyntaxError as e:
            return f"is not valid Python: {e}"
    return None


def error_lines(err):
    lines = [line for line in err.splitlines() if line.strip()]
    errors = [line for line in lines if line.startswith("flowire: error:")]
    others = [line for line in lines if not line.startswith(("flowire: error:", "flowire: warning:"))]
    return errors, others


def check_one_error_line(c, label, err, must_contain=()):
    errors, others = error_lines(err)
    c.check(len(errors) == 1, f"{label}: {len(errors)} stderr lines start with 'flowire: error:' (expected one)"
            + (f"; stderr begins: {first_line(err)!r}" if not errors else ""))
    c.check(not others, f"{label}: stderr has {len(others)} other lines, first: {others[0][:200]!r}" if others else "")
    for what, text in must_contain:
        c.check(any(text in e for e in errors), f"{label}: the error line does not name {what} ({text!r}): "
                f"{errors[0][:300] if errors else '(none)'!r}")


def first_line(text):
    for line in text.splitlines():
        if line.strip():
            return line[:300]
    return ""


def parse_trace(path):
    """[(n, op, failed, path)] of a FLOWIRE_FAIL_TRACE file."""
    calls = []
    if not os.path.exists(path):
        return calls
    with open(path, errors="replace") as f:
        for line in f:
            parts = line.rstrip("\n").split(" ", 3)
            if len(parts) == 4:
                calls.append((int(parts[0]), parts[1], parts[2] == "fail", parts[3]))
    return calls


def read_count(path, pid):
    """Counted calls of process `pid` from a FLOWIRE_FAIL_COUNT file (None if it did not report)."""
    if not os.path.exists(path):
        return None
    with open(path) as f:
        for line in f:
            p, n = line.split()
            if int(p) == pid:
                return int(n)
    return None


def rc_text(rc):
    if rc is None:
        return "still running"
    if rc < 0:
        try:
            return f"killed by {signal.Signals(-rc).name}"
        except ValueError:
            return f"killed by signal {-rc}"
    return f"exit status {rc}"


def compare_with_reference(c, label, folder, ref, skip=()):
    """Every output file in `folder` is byte-identical to `ref`'s (except those in `skip`)."""
    for rel in output_files(folder):
        if os.path.basename(rel) in skip:
            continue
        r = os.path.join(ref, rel)
        if not c.check(os.path.exists(r), f"{label}: {rel} is not an output of the undisturbed run"):
            continue
        a, b = read_bytes(os.path.join(folder, rel)), read_bytes(r)
        c.check(a == b, f"{label}: {rel} is not the undisturbed run's ({len(a)} bytes, the undisturbed "
                f"run's {len(b)}{'; a cut-off copy' if b.startswith(a) else ''})")


def check_no_partials(c, label, folder):
    p = partial_files(folder)
    c.check(not p, f"{label}: {len(p)} temporaries left in the folder: {', '.join(p[:5])}")
    s = stray_hidden_files(folder)
    c.check(not s, f"{label}: stray hidden files left in the folder: {', '.join(s[:5])}")


def check_complete(c, label, folder, ref=None, since=None):
    """Every output file in `folder` (modified after `since`, a time.time(), if given) is
    complete; frame files also equal `ref`'s, if given."""
    for rel in output_files(folder):
        if since is not None and os.stat(os.path.join(folder, rel)).st_mtime < since:
            continue
        why = incomplete(os.path.join(folder, rel))
        c.check(why is None, f"{label}: {rel} {why}")
        if ref and why is None and FRAME_NAME.match(os.path.basename(rel)):
            r = os.path.join(ref, rel)
            if os.path.exists(r):
                c.check(read_bytes(os.path.join(folder, rel)) == read_bytes(r),
                        f"{label}: frame {rel} differs from the undisturbed run's")


# ---------------------------------------------------------------- write failures


def check_write_protocol(c, label, calls, pid):
    """Every counted call of an undisturbed run went to a temporary `.<name>.<pid>.<hex>.partial`
    of that process (or the run lock), one name per file, and every temporary was fsynced."""
    synced, bad, names, closes = set(), [], {}, {}
    for _, op, _, path in calls:
        base = os.path.basename(path.removesuffix(" (deleted)"))
        if base == LOCK:
            continue
        m = TEMP_NAME.match(base)
        if not m or int(m.group(2)) != pid:
            bad.append(f"{op} of {base}")
            continue
        names.setdefault(m.group(1), set()).add(base)
        if op in ("fsync", "fdatasync"):
            synced.add(base)
        if op in ("close", "fclose"):
            closes[base] = closes.get(base, 0) + 1
    c.check(not bad, f"{label}: writes not to a temporary .<name>.{pid}.<hex>.partial: {', '.join(bad[:4])}"
            + (f" (and {len(bad) - 4} more)" if len(bad) > 4 else ""))
    reused = sorted(t for t, n in closes.items() if n > 1)
    c.check(not reused, f"{label}: one temporary name written more than once: {', '.join(reused[:4])}")
    unsynced = sorted({t for temps in names.values() for t in temps} - synced)
    c.check(not unsynced, f"{label}: temporaries never fsynced: "
            f"{', '.join(unsynced[:4])}" + (f" (and {len(unsynced) - 4} more)" if len(unsynced) > 4 else ""))


def pick_fail_points(calls, budget, rng):
    """Which counted calls to fail: the first and last call of every file, then the first sync
    and close of every file, then others at random; at most `budget`."""
    by_file = {}
    for n, op, _, path in calls:
        by_file.setdefault(target_name(path), []).append((n, op))
    tiers = [set(), set(), set()]
    if calls:
        tiers[0].update({calls[0][0], calls[-1][0]})
    for calls_of in by_file.values():
        tiers[0].update({calls_of[0][0], calls_of[-1][0]})
        seen = set()
        for n, op in calls_of:
            kind = "sync" if op in ("fsync", "fdatasync") else "close" if op in ("close", "fclose") else "write"
            if kind != "write" and kind not in seen:
                seen.add(kind)
                tiers[1].add(n)
    tiers[2] = {n for n, _, _, _ in calls}
    chosen = set()
    for tier in tiers:
        rest = sorted(tier - chosen)
        room = budget - len(chosen)
        if room <= 0:
            break
        if len(rest) <= room:
            chosen.update(rest)
        elif tier is tiers[2]:
            chosen.update(rng.sample(rest, room))
        else:  # evenly spread over the tier
            chosen.update(rest[(i * len(rest)) // room] for i in range(room))
    return sorted(chosen)


def eligible(call):
    """A failing close or sync of the run lock loses no output: not a point to fail at."""
    _, op, _, path = call
    return not (target_name(path) == LOCK and op in ("close", "fclose", "fsync", "fdatasync"))


def write_failure_run(args, tool, c):
    work = fresh(os.path.join(args.work, "write_failure_run"))
    scene = os.path.join(tool.examples, "branch_selection", "scene.yaml")
    # 0.1 s of a wire in a Y with flow: csv, a .vtp series of 3 frames each for the network and
    # the wire, .pvd files, view.py and summary.json, in well under a second.
    sets = ["solve.duration=0.1s", "output.every=0.05s", "output.csv=true", "output.vtk=true", "output.png=false"]

    def argv(out):
        a = ["run", scene, "--out", out]
        for s in sets:
            a += ["--set", s]
        return a

    refs, traces = [], []
    for i in (1, 2):
        ref = fresh(os.path.join(work, f"reference{i}"))
        trace = os.path.join(work, f"reference{i}.trace")
        t0 = time.monotonic()
        r = tool.run(argv(ref), fail={"dir": ref, "ops": "write,sync,close", "trace": trace})
        elapsed = time.monotonic() - t0
        if not c.check(r.rc == 0, f"undisturbed run {i}: {rc_text(r.rc)}: {first_line(r.err)!r}"):
            return
        status, _, problem = read_summary(ref)
        c.check(status == "ok", f"undisturbed run {i}: summary.json status {status!r} {problem or ''}")
        check_no_partials(c, f"undisturbed run {i}", ref)
        refs.append(ref)
        traces.append(parse_trace(trace))
        check_write_protocol(c, f"undisturbed run {i}", traces[-1], r.pid)
        print(f"undisturbed run {i}: {len(traces[-1])} counted calls, {len(output_files(ref))} files, {elapsed:.2f} s")
    files = output_files(refs[0])
    kinds = {".csv": 0, ".vtp": 0, ".pvd": 0}
    for f in files:
        for k in kinds:
            kinds[k] += f.endswith(k)
    c.check(kinds[".csv"] >= 2 and kinds[".vtp"] >= 4 and kinds[".pvd"] >= 1 and "summary.json" in files,
            f"the scene does not write the expected kinds of output (csv, a .vtp series, .pvd, summary.json): {files}")
    c.check(files == output_files(refs[1]), "two undisturbed runs write different sets of files")
    for rel in files:
        if rel in NOT_REPRODUCIBLE or not os.path.exists(os.path.join(refs[1], rel)):
            continue
        c.check(read_bytes(os.path.join(refs[0], rel)) == read_bytes(os.path.join(refs[1], rel)),
                f"two undisturbed runs write different {rel} (not reproducible: it cannot be checked byte-wise)")
    for rel, why in NOT_REPRODUCIBLE.items():
        print(f"  {rel} is compared by its status only: it {why}")
    shape = [(op, target_name(p)) for _, op, _, p in traces[0]]
    if shape != [(op, target_name(p)) for _, op, _, p in traces[1]]:
        c.note("the two undisturbed runs made different sequences of counted calls: a fail point may hit "
               "a different call than planned (each case is checked by the call that actually failed)")
    calls = [call for call in traces[0] if eligible(call)]
    if not c.check(len(calls) > 0, "the undisturbed run made no counted write into its folder (is the library "
                   "loaded?)"):
        return
    rng = random.Random(args.seed)
    points = pick_fail_points(calls, args.budget, rng)
    print(f"failing at {len(points)} of {len(calls)} counted calls (seed {args.seed}): {points}")
    ops_of = {n: (op, target_name(p)) for n, op, _, p in traces[0]}
    t_start = time.monotonic()
    for k in points:
        out = fresh(os.path.join(work, f"fail_at_{k}"))
        trace = os.path.join(work, f"fail_at_{k}.trace")
        r = tool.run(argv(out), fail={"dir": out, "ops": "write,sync,close", "at": k, "trace": trace}, timeout=60)
        op, name = ops_of.get(k, ("?", "?"))
        label = f"fail at call {k} ({op} of {name})"
        before = c.failed
        failed_calls = [call for call in parse_trace(trace) if call[2]]
        if not c.check(not r.timed_out, f"{label}: did not end within 60 s"):
            continue
        if not failed_calls:
            c.fail(f"{label}: no call failed (the run made fewer counted calls than the undisturbed one); "
                   f"{rc_text(r.rc)}")
            continue
        first = failed_calls[0]
        failed_name = target_name(first[3])
        if failed_name != name:
            label = f"fail at call {k} ({first[1]} of {failed_name})"
        c.check(r.rc == 2, f"{label}: {rc_text(r.rc)} (expected exit status 2)")
        if failed_name == LOCK:
            check_one_error_line(c, label, r.err, [("the output folder", out)])
        else:
            check_one_error_line(c, label, r.err, [("the file", failed_name)])
        check_no_partials(c, label, out)
        compare_with_reference(c, label, out, refs[0], skip=NOT_REPRODUCIBLE)
        status, _, problem = read_summary(out)
        c.check(problem is None, f"{label}: {problem}")
        c.check(status != "ok", f"{label}: summary.json says \"ok\" after a failed write")
        if c.failed == before:
            shutil.rmtree(out, ignore_errors=True)
            os.remove(trace)
    print(f"{len(points)} failing runs in {time.monotonic() - t_start:.1f} s")


# ---------------------------------------------------------------- convert and compare

NETWORK_YAML = """\
branches:
  - name: trunk
    points: [[0, 0, 0, 0.004], [0.02, 0, 0, 0.004], [0.04, 0, 0, 0.0038], [0.06, 0, 0, 0.0036]]
  - name: left
    points: [[0.06, 0, 0, 0.003], [0.08, 0.01, 0, 0.0028], [0.1, 0.02, 0, 0.0025]]
  - name: right
    points: [[0.06, 0, 0, 0.003], [0.08, -0.01, 0, 0.0028], [0.1, -0.02, 0, 0.0025]]
"""


def single_output_failures(c, tool, work, label, make_argv, out_name, budget, rng):
    """A command that writes one file: every counted call of it fails in turn."""
    refs = []
    trace = None
    for i in (1, 2):
        folder = fresh(os.path.join(work, f"{label}_reference{i}"))
        tr = os.path.join(work, f"{label}_reference{i}.trace")
        r = tool.run(make_argv(os.path.join(folder, out_name)), fail={"dir": folder, "ops": "write,sync,close",
                                                                     "trace": tr})
        if not c.check(r.rc == 0 and os.path.exists(os.path.join(folder, out_name)),
                       f"{label}: undisturbed run {i}: {rc_text(r.rc)}: {first_line(r.err)!r}"):
            return
        check_no_partials(c, f"{label}: undisturbed run {i}", folder)
        refs.append(read_bytes(os.path.join(folder, out_name)))
        check_write_protocol(c, f"{label}: undisturbed run {i}", parse_trace(tr), r.pid)
        trace = trace or parse_trace(tr)
    c.check(refs[0] == refs[1], f"{label}: two undisturbed runs write different {out_name}")
    calls = [call for call in trace if eligible(call)]
    if not c.check(calls, f"{label}: the undisturbed run made no counted write (is the library loaded?)"):
        return
    points = pick_fail_points(calls, budget, rng)
    print(f"{label}: {len(refs[0])} bytes in {len(calls)} counted calls "
          f"({', '.join(op for _, op, _, _ in calls)}); failing at {points}")
    for k in points:
        for existing in (False, True):
            if existing and k not in (points[0], points[-1]):
                continue
            folder = fresh(os.path.join(work, f"{label}_fail_at_{k}{'_existing' if existing else ''}"))
            out = os.path.join(folder, out_name)
            old = b"previous contents\n"
            if existing:
                with open(out, "wb") as f:
                    f.write(old)
            tr = os.path.join(work, f"{label}_fail_at_{k}.trace")
            if os.path.exists(tr):
                os.remove(tr)
            r = tool.run(make_argv(out), fail={"dir": folder, "ops": "write,sync,close", "at": k, "trace": tr},
                         timeout=60)
            failed = [call for call in parse_trace(tr) if call[2]]
            what = f"{label}: fail at call {k} ({failed[0][1] if failed else '?'})" + \
                (f" over an existing {out_name}" if existing else "")
            if not c.check(not r.timed_out, f"{what}: did not end within 60 s"):
                continue
            if not c.check(failed, f"{what}: no call failed; {rc_text(r.rc)}"):
                continue
            c.check(r.rc == 2, f"{what}: {rc_text(r.rc)} (expected exit status 2)")
            check_one_error_line(c, what, r.err, [("the file", out_name)])
            check_no_partials(c, what, folder)
            if existing:
                now = read_bytes(out) if os.path.exists(out) else None
                c.check(now == old, f"{what}: {out_name} was "
                        + ("removed" if now is None else f"changed ({len(now)} bytes)") + ": it must stay as it was")
            else:
                size = os.path.getsize(out) if os.path.exists(out) else None
                c.check(size is None, f"{what}: {out_name} is left behind ({size} bytes of {len(refs[0])}"
                        + (", 0-byte" if size == 0 else ", cut off" if size and size < len(refs[0]) else "") + ")")
                left = [f for f in all_files(folder) if f != out_name]
                c.check(not left, f"{what}: files left in the folder: {', '.join(left[:5])}")


def write_failure_convert_compare(args, tool, c):
    work = fresh(os.path.join(args.work, "write_failure_convert_compare"))
    rng = random.Random(args.seed)
    network = os.path.join(work, "network.yaml")
    with open(network, "w") as f:
        f.write(NETWORK_YAML)
    for ext in ("vtp", "yaml"):
        single_output_failures(c, tool, work, f"convert_to_{ext}",
                               lambda out: ["network", "convert", network, out, "--max-segment-length", "0.002"],
                               f"network.{ext}", args.budget, rng)
    # Two tip traces: the J tip turned 0 and 180 degrees at the base.
    scene = os.path.join(tool.examples, "branch_selection", "scene.yaml")
    traces = []
    for angle in ("0deg", "180deg"):
        out = fresh(os.path.join(work, f"trace_{angle}"))
        r = tool.run(["run", scene, "--out", out, "--set", "solve.duration=0.2s", "--set", "output.vtk=false",
                      "--set", f"insertion.rotation_angle={angle}"])
        if not c.check(r.rc == 0, f"the run for the {angle} tip trace: {rc_text(r.rc)}: {first_line(r.err)!r}"):
            return
        traces.append(os.path.join(out, "tip_trace.csv"))
    single_output_failures(c, tool, work, "compare",
                           lambda out: ["compare", traces[0], traces[1], "--out", out, "--spacing", "0.5mm",
                                        "--rows", "1mm"],
                           "rms.csv", args.budget, rng)


# ---------------------------------------------------------------- runs that hold a folder

LONG_SETS = ["solve.duration=30s", "output.every=0.25s", "output.csv=true", "output.vtk=true", "output.png=false"]
SHORT_SETS = ["solve.duration=1s", "output.every=0.25s", "output.csv=true", "output.vtk=true", "output.png=false"]


def arch_argv(tool, out, sets):
    a = ["run", os.path.join(tool.examples, "aortic_arch", "scene.yaml"), "--out", out]
    for s in sets:
        a += ["--set", s]
    return a


def wait_started(proc, folder, since, timeout=60):
    """Wait until the run `proc` is under way in `folder`: "running" once summary.json says
    "running" with its pid; "writing" if, before that, it wrote an output file (modified after
    `since`, a time.time()); "ended" if it ended first; "timeout"."""
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        status, s, _ = read_summary(folder)
        if status == "running" and s.get("pid") == proc.pid:
            return "running"
        if proc.poll() is not None:
            return "ended"
        for rel in output_files(folder):
            try:
                if rel != "summary.json" and os.stat(os.path.join(folder, rel)).st_mtime >= since:
                    return "writing"
            except OSError:
                pass
        time.sleep(0.005)
    return "timeout"


def timed_long_run(c, tool, folder, label, sets=LONG_SETS, fail=None):
    """An undisturbed long run: (the seconds it ran after it was under way, its steps), or None."""
    t0, since = time.monotonic(), time.time()
    p = tool.popen(arch_argv(tool, folder, sets), fail)
    started = wait_started(p, folder, since)
    t1 = time.monotonic()
    out, err = p.communicate(timeout=600)
    t2 = time.monotonic()
    if not c.check(p.returncode == 0, f"{label}: {rc_text(p.returncode)}: {first_line(err)!r}"):
        return None
    c.check(started == "running", f"{label}: summary.json never said \"running\" with the run's pid while it ran")
    status, s, problem = read_summary(folder)
    c.check(status == "ok", f"{label}: summary.json status {status!r} {problem or ''}")
    check_no_partials(c, label, folder)
    print(f"{label}: {t2 - t0:.2f} s ({t2 - t1:.2f} s after it was under way: {started}), "
          f"{len(output_files(folder))} files")
    return (t2 - t1 if started in ("running", "writing") else t2 - t0), (s or {}).get("steps")


def concurrent_runs(args, tool, c):
    work = fresh(os.path.join(args.work, "concurrent_runs"))
    ref = fresh(os.path.join(work, "reference"))
    if timed_long_run(c, tool, ref, "undisturbed run") is None:
        return
    folder = fresh(os.path.join(work, "shared"))
    since = time.time()
    first = tool.popen(arch_argv(tool, folder, LONG_SETS))
    try:
        started = wait_started(first, folder, since)
        c.check(started == "running", f"first run: summary.json did not say \"running\" with pid {first.pid} "
                f"before the run wrote outputs ({started})")
        if started not in ("running", "writing"):
            return
        count = os.path.join(work, "second.count")
        trace = os.path.join(work, "second.trace")
        for p in (count, trace):
            if os.path.exists(p):
                os.remove(p)
        second = tool.run(arch_argv(tool, folder, LONG_SETS),
                          fail={"dir": folder, "ops": "write,sync,close", "count": count, "trace": trace},
                          timeout=60)
        c.check(first.poll() is None or second.rc != 2, "the first run ended before the second was refused: "
                "the check is void (make the first run longer)")
        label = f"second run while pid {first.pid} holds the folder"
        c.check(second.rc == 2, f"{label}: {rc_text(second.rc)} (expected exit status 2); "
                f"stdout {first_line(second.out)!r}")
        check_one_error_line(c, label, second.err,
                             [("'another flowire run'", "another flowire run"), ("the holder's pid", str(first.pid))])
        n = read_count(count, second.pid)
        writes = [call for call in parse_trace(trace) if call[1] not in ("close", "fclose")]
        c.check(n is not None, f"{label}: it did not report its counted calls (did it crash?)")
        c.check(not writes, f"{label}: it wrote into the folder: "
                + ", ".join(f"{op} of {target_name(p)}" for _, op, _, p in writes[:5]))
        mine = [f for f in all_files(folder) if f".{second.pid}." in f]
        c.check(not mine, f"{label}: it left files in the folder: {', '.join(mine[:5])}")
        if first.poll() is None:
            status, s, _ = read_summary(folder)
            c.check(status == "running" and s.get("pid") == first.pid,
                    f"{label}: summary.json no longer says \"running\" with the first run's pid: {status!r}")
        out, err = first.communicate(timeout=600)
    finally:
        if first.poll() is None:
            first.kill()
            first.wait()
    label = "first run"
    c.check(first.returncode == 0, f"{label}: {rc_text(first.returncode)}: {first_line(err)!r}")
    status, _, problem = read_summary(folder)
    c.check(status == "ok", f"{label}: summary.json status {status!r} {problem or ''}")
    check_no_partials(c, label, folder)
    compare_with_reference(c, label, folder, ref, skip=NOT_REPRODUCIBLE)
    c.check(output_files(folder) == output_files(ref), f"{label}: wrote other files than an undisturbed run: "
            f"{sorted(set(output_files(folder)) ^ set(output_files(ref)))[:5]}")
    # The lock goes with the run: the next run on the folder is not refused.
    r = tool.run(arch_argv(tool, folder, SHORT_SETS), timeout=120)
    c.check(r.rc == 0, f"a run after the first ended: {rc_text(r.rc)}: {first_line(r.err)!r}")
    status, _, problem = read_summary(folder)
    c.check(status == "ok", f"a run after the first ended: summary.json status {status!r} {problem or ''}")


# ---------------------------------------------------------------- signals

EXPECTED_STATUS = {signal.SIGINT: (130, -signal.SIGINT), signal.SIGTERM: (143, -signal.SIGTERM),
                   signal.SIGKILL: (-signal.SIGKILL,)}


def dead_pid():
    """The pid of a process that has ended."""
    p = subprocess.Popen(["true"])
    p.wait()
    return p.pid


def signals(args, tool, c):
    work = fresh(os.path.join(args.work, "signals"))
    ref = fresh(os.path.join(work, "reference"))
    long_run = timed_long_run(c, tool, ref, "undisturbed run")
    if long_run is None:
        return
    # The same run on a slow disk (every write into the folder first sleeps): most of it is
    # spent writing files, so that most signals arrive while a temporary is open.
    slow_ref = fresh(os.path.join(work, "reference_slow_disk"))
    slow_run = timed_long_run(c, tool, slow_ref, "undisturbed run on a slow disk", SLOW_SETS, slow_disk(slow_ref))
    if slow_run is None:
        return
    rng = random.Random(args.seed)
    for sig in (signal.SIGINT, signal.SIGTERM, signal.SIGKILL):
        folder = fresh(os.path.join(work, sig.name))
        r = tool.run(arch_argv(tool, folder, SHORT_SETS))
        if not c.check(r.rc == 0, f"{sig.name}: the first run on the folder: {rc_text(r.rc)}: {first_line(r.err)!r}"):
            continue
        missed = 0
        for trial in range(1, 2 * args.trials + 1):
            slow = trial > args.trials
            missed += signal_trial(c, tool, rng, sig, folder, ref, trial, slow_run if slow else long_run,
                                   SLOW_SETS if slow else LONG_SETS, slow_disk(folder) if slow else None)
        c.check(missed < 2 * args.trials, f"{sig.name}: every trial ended before its signal (the run is too short)")


SLOW_SETS = ["solve.duration=10s", "output.every=0.25s", "output.csv=true", "output.vtk=true", "output.png=false"]


def slow_disk(folder):
    return {"dir": folder, "ops": "write,sync,close", "delay_us": 30}


def signal_trial(c, tool, rng, sig, folder, ref, trial, undisturbed, sets, fail):
    """One run on `folder` signalled at a random time, then a rerun; 1 if the run ended first.
    `undisturbed`: (seconds, steps) of the same run undisturbed."""
    t_run, all_steps = undisturbed
    delay = rng.uniform(0.02, 0.9) * t_run
    label = f"{sig.name} trial {trial} ({delay:.2f} s into the run{', slow disk' if fail else ''})"
    for rel in partial_files(folder):  # left by an earlier trial (and reported there)
        os.remove(os.path.join(folder, rel))
    since = time.time()
    p = tool.popen(arch_argv(tool, folder, sets), fail, stdout=subprocess.DEVNULL)
    try:
        started = wait_started(p, folder, since)
        c.check(started == "running", f"{label}: summary.json did not say \"running\" with pid {p.pid} "
                f"before the run wrote outputs ({started})")
        time.sleep(delay)
        if p.poll() is not None:
            c.note(f"{label}: the run ended ({rc_text(p.returncode)}) before the signal")
            p.communicate()
            return 1
        p.send_signal(sig)
        t_sig = time.monotonic()
        try:
            _, err = p.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            c.fail(f"{label}: still running 60 s after {sig.name}")
            p.kill()
            _, err = p.communicate()
        took = time.monotonic() - t_sig
    finally:
        if p.poll() is None:
            p.kill()
            p.wait()
    status, summary, problem = read_summary(folder)
    # The signal may come as the run ends: its summary then says "ok" with every step done.
    finished = status == "ok" and summary.get("steps") == all_steps
    if finished:
        c.note(f"{label}: the signal came after the run had finished ({rc_text(p.returncode)})")
    expected = EXPECTED_STATUS[sig] + ((0,) if finished else ())
    c.check(p.returncode in expected, f"{label}: {rc_text(p.returncode)} (expected "
            + " or ".join(rc_text(s) for s in expected) + f"); stderr {first_line(err)!r}")
    partials = partial_files(folder)
    if sig != signal.SIGKILL:
        c.check(not partials, f"{label}: {len(partials)} temporaries left: {', '.join(partials[:5])}")
    c.check(problem is None, f"{label}: {problem}")
    allowed = ("running",) if sig == signal.SIGKILL else ("interrupted", "running")
    allowed += ("ok",) if finished else ()
    c.check(status in allowed,
            f"{label}: summary.json status {status!r} (expected " + " or ".join(repr(a) for a in allowed) + ")")
    check_complete(c, label, folder, ref, since)
    print(f"{label}: {rc_text(p.returncode)} {took:.2f} s after the signal; summary {status!r}; "
          f"{len(partials)} temporaries left")
    # A temporary of a process that no longer exists, as a power cut leaves it.
    stale = os.path.join(folder, f".wire_00001.vtp.{dead_pid()}.00c0ffee00c0ffee.partial")
    with open(stale, "wb") as f:
        f.write(b"<?xml version=\"1.0\"?>\n<VTKFile")
    since = time.time()
    rerun = tool.run(arch_argv(tool, folder, SHORT_SETS), timeout=120)
    label = f"{sig.name} trial {trial}: the rerun"
    c.check(rerun.rc == 0, f"{label}: {rc_text(rerun.rc)}: {first_line(rerun.err)!r}")
    status, _, problem = read_summary(folder)
    c.check(status == "ok", f"{label}: summary.json status {status!r} {problem or ''}")
    partials = partial_files(folder)
    c.check(not partials, f"{label}: {len(partials)} temporaries of dead processes left: {', '.join(partials[:5])}")
    check_complete(c, label, folder, ref, since)
    return 0


# ----------------------------------------------------------------


CASES = {
    "write_failure_run": write_failure_run,
    "write_failure_convert_compare": write_failure_convert_compare,
    "concurrent_runs": concurrent_runs,
    "signals": signals,
}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("case", choices=sorted(CASES))
    ap.add_argument("--flowire", required=True, help="the flowire program")
    ap.add_argument("--preload", required=True, help="the fail_write LD_PRELOAD library")
    ap.add_argument("--examples", required=True, help="the examples folder of the source tree")
    ap.add_argument("--work", required=True, help="a folder for the runs (cleared)")
    ap.add_argument("--seed", type=int, default=1, help="seed of the fail points and signal times")
    ap.add_argument("--budget", type=int, default=72, help="at most this many fail points per command")
    ap.add_argument("--trials", type=int, default=2, help="runs interrupted per signal, on each kind of disk")
    args = ap.parse_args()
    for what, path in (("--flowire", args.flowire), ("--preload", args.preload)):
        if not os.path.isfile(path):
            sys.exit(f"fault_injection.py: {what} {path} does not exist")
    c = Checks(args.case)
    t0 = time.monotonic()
    CASES[args.case](args, Tool(args), c)
    print(f"{args.case}: {c.total - c.failed} of {c.total} checks passed in {time.monotonic() - t0:.1f} s")
    sys.exit(1 if c.failed else 0)


if __name__ == "__main__":
    main()
