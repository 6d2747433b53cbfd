#!/usr/bin/env python3
"""./roomprobe fuzz TARGET|all [--runs N] [--seconds S] [--replay]: the libFuzzer targets of tests/fuzz/.

Runs inside the toolchain. Builds the targets (scons fuzz=yes: clang, the core instrumented,
AddressSanitizer and UndefinedBehaviorSanitizer), makes each target's seed corpus when it has
none (build/fuzz/corpus/TARGET/: files of a synthetic recording, small PNGs and YAML files
written here, and what the recording, capture and photometric targets write themselves under
ROOMPROBE_FUZZ_SEED), then fuzzes each target on its corpus. A crash or a broken
invariant leaves its input in build/fuzz/crashes/TARGET/ and fails the run. Each run adds a line
to build/fuzz/ledger.tsv, so that executions add up across runs and machines: --ledger prints
the totals, --add-logs counts libFuzzer logs of runs made elsewhere (TARGET*.log). Ends with one
line: 'summary: targets=K execs=N crashes=C seconds=S'.
"""

import argparse
import datetime
import io
import os
import re
import shutil
import struct
import subprocess
import sys
import tempfile
import time
import zipfile
import zlib

REPO = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(REPO, "tools"))
import rp_godot as rp  # noqa: E402

TARGETS = ["rig", "room", "index", "png", "depth", "exr", "recording", "synth", "capture", "photometric", "board", "cli", "trajectory", "zip"]
# Inputs longer than this are cut (libFuzzer's -max_len): a whole 640x480 frame seed would make each
# execution slow; its header and first rows are what the decoders' checks read.
MAX_LEN = {"png": 65536, "depth": 65536, "exr": 65536}
FUZZ_DIR = os.path.join(rp.BUILD, "fuzz")
# The synthetic recording the seeds come from: the test suite's fixture, else one made here.
FIXTURE = os.path.join(rp.BUILD, "test-data", "living_room_1s")
SEED_RECORDING = os.path.join(rp.BUILD, "test-data", "fuzz-seed-recording")
EXECS = re.compile(r"^stat::number_of_executed_units:\s*(\d+)")
LEDGER = os.path.join(FUZZ_DIR, "ledger.tsv")
LEDGER_HEADER = "utc\ttarget\texecutions\tseconds\tcrashes\twhere\n"
# The recording target's bundle replaces these template files; the synthetic recording's own
# text files go in under the same names.
BUNDLE_TEXT = ["rig.yaml", "room.yaml", "rgb.txt", "depth.txt", "fisheye.txt"]
REPLAY_TIMEOUT_S = 300  # a target's whole corpus replay; the seeds take a second or two
INDEX_LINES = 40  # an index seed keeps its first lines: the fuzzer mutates, it need not read a whole sweep


def png_bytes(width, height, bit_depth, colour_type, rows):
    """A minimal PNG (IHDR, one IDAT, IEND) of the given raw rows, each with filter byte 0."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    raw = b"".join(b"\x00" + row for row in rows)
    header = struct.pack(">IIBBBBB", width, height, bit_depth, colour_type, 0, 0, 0)
    return b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", header) + chunk(b"IDAT", zlib.compress(raw)) + chunk(b"IEND", b"")


def small_pngs():
    """Small PNGs of each kind a recording holds: 8-bit RGB, 8-bit gray, 16-bit depth (with the
    0 and 65535 'no reading' values), gray with alpha."""
    rgb = [bytes((x * 30 + y) % 256 for x in range(8) for _ in range(3)) for y in range(6)]
    gray = [bytes((x * 20 + y * 7) % 256 for x in range(8)) for y in range(6)]
    depth = [b"".join(struct.pack(">H", [0, 65535, 500 + 37 * x + y][min(x, 2)]) for x in range(8)) for y in range(6)]
    gray_alpha = [bytes(v for x in range(8) for v in ((x * 20) % 256, 255)) for _ in range(6)]
    return {"rgb8.png": png_bytes(8, 6, 8, 2, rgb), "gray8.png": png_bytes(8, 6, 8, 0, gray),
            "depth16.png": png_bytes(8, 6, 16, 0, depth), "gray_alpha.png": png_bytes(8, 6, 8, 4, gray_alpha)}


def seed_recording():
    """A synthetic recording to take seeds from (the tests' fixture, or a short one made now)."""
    if os.path.isfile(os.path.join(FIXTURE, "rig.yaml")):
        return FIXTURE
    if not os.path.isfile(os.path.join(SEED_RECORDING, "rig.yaml")):
        print(f"fuzz: synthesising a short recording for the seeds into {SEED_RECORDING}", flush=True)
        subprocess.run(["scons", "-Q", f"-j{os.cpu_count() or 2}", "build/bin/roomprobe_synth"], cwd=REPO, check=True,
                       stdout=subprocess.DEVNULL)
        shutil.rmtree(SEED_RECORDING, ignore_errors=True)
        subprocess.run([os.path.join(rp.BUILD, "bin", "roomprobe_synth"), "--scene", "living_room", "--seconds", "0.3",
                        "--no-calibration", "--out", SEED_RECORDING], cwd=REPO, check=True, stdout=subprocess.DEVNULL)
    return SEED_RECORDING


def first_lines(path, count):
    with open(path, "rb") as f:
        return b"".join(f.readlines()[:count])


def first_file(folder, suffix):
    names = sorted(n for n in os.listdir(folder) if n.endswith(suffix)) if os.path.isdir(folder) else []
    return os.path.join(folder, names[0]) if names else None


def target_seed(target, path):
    """Has TARGET write its own seed to path (ROOMPROBE_FUZZ_SEED: the recording target's template,
    the capture target's capture.txt, the photometric target's photometric.yaml); returns its bytes."""
    subprocess.run([binary(target)], env=dict(os.environ, ROOMPROBE_FUZZ_SEED=path), check=True,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(path, "rb") as f:
        data = f.read()
    if not data:  # the targets once exited before their stream was flushed, leaving empty seeds
        sys.exit(f"fuzz: {target} wrote an empty seed ({path})")
    return data


# Small valid files written by hand, for the targets whose files a short recording may lack
# (fuzz-seed-recording is made without calibration/).
BOARD_YAML = b"%YAML:1.0\n---\ninner_corners_x: 9\ninner_corners_y: 6\nsquare_m: 0.035\n"
BOARDS_YAML = (b"%YAML:1.0\n---\nroomprobe_calibration_views: 1\nboard:\n   inner_corners_x: 7\n   inner_corners_y: 5\n"
               b"   square_m: 2.5000000000000001e-02\n")
SYNTH_YAML = (b"%YAML:1.0\n---\nroomprobe_synth: 1\nscene: two_rooms\nscene_panorama: none\ntrajectory: room_sweep\n"
              b"duration_s: 2.5\nlight_switch_s: -1\nfisheye_vignetting_edge_gain: 0.25\nfisheye_exposure: 0.5\n"
              b"fisheye_reference_exposure_us: 5000.\nfisheye_tone_curve: log\nfisheye_channel_gains: [ 1.25, 1., 0.75 ]\n"
              b"rgb_tone_curve: srgb\nrgb_exposure: 2.\n")

CLI_ARGVS = {
    "options.argv": [b"--threads", b"2", b"--square-m", b"0.035", b"--seconds", b"0.3", b"--offset", b"0",
                     b"--gains", b"1.1,1,0.85", b"--stops", b"-5,0"],
    "bad_values.argv": [b"--threads", b"100000", b"--square-m", b"nan", b"--seconds", b"1e999", b"--gains", b"1,2",
                        b"--stops", b"1,,2", b"99999999999999999999", b"--offset"],
}


def template_files():
    """The recording target's template (small frames of every kind), as {relative path: bytes}."""
    data = target_seed("recording", os.path.join(FUZZ_DIR, "template.bundle"))
    files = {}
    for part in data[2:].split(b"\n@@"):
        name, _, body = part.partition(b"\n")
        files[name.decode()] = body
    return files


def make_corpus(target, corpus):
    """Writes TARGET's seeds into corpus/ (called when it is missing or empty)."""
    os.makedirs(corpus, exist_ok=True)
    recording = seed_recording()
    seeds = {}
    if target == "rig":
        seeds["synthetic_rig.yaml"] = open(os.path.join(recording, "rig.yaml"), "rb").read()
    elif target == "room":
        seeds["synthetic_room.yaml"] = open(os.path.join(recording, "room.yaml"), "rb").read()
    elif target == "index":
        for root, _, names in os.walk(recording):
            for name in names:
                if name.endswith(".txt"):
                    rel = os.path.relpath(os.path.join(root, name), recording).replace("/", "_")
                    seeds[rel] = first_lines(os.path.join(root, name), INDEX_LINES)
    elif target in ("png", "depth"):
        for kind in ("rgb", "depth") if target == "png" else ("depth",):
            for suffix in (".png", ".zst"):  # PNG frames, raw frames (the writer's default)
                path = first_file(os.path.join(recording, kind), suffix)
                if path:
                    seeds[f"synthetic_{kind}{suffix}"] = open(path, "rb").read()
        seeds.update(small_pngs() if target == "png" else {"depth16.png": small_pngs()["depth16.png"]})
        for name, body in template_files().items():
            if name.endswith((".png", ".zst")) and (target == "png" or name.startswith("depth/")):
                seeds["template_" + name.replace("/", "_")] = body
    elif target == "exr":
        for folder in ("fisheye", "groundtruth/cubemaps"):
            path = first_file(os.path.join(recording, folder), ".exr")
            if path:
                seeds[folder.replace("/", "_") + ".exr"] = open(path, "rb").read()
        for name, body in template_files().items():
            if name.endswith(".exr"):
                seeds["template_" + name.replace("/", "_")] = body
    elif target == "recording":
        template_files()  # writes FUZZ_DIR/template.bundle
        shutil.copy(os.path.join(FUZZ_DIR, "template.bundle"), os.path.join(corpus, "template.bundle"))
        parts = []
        for name in BUNDLE_TEXT:
            path = os.path.join(recording, name)
            if os.path.isfile(path):
                parts.append(b"@@" + name.encode() + b"\n" + (first_lines(path, INDEX_LINES) if name.endswith(".txt") else open(path, "rb").read()))
        seeds["synthetic_text.bundle"] = b"\n".join(parts)
    elif target == "synth":
        text = open(os.path.join(recording, "synth.yaml"), "rb").read()
        seeds["synthetic_synth.yaml"] = text
        # Without the panorama (a 1k HDR read each time the scene is built), and by hand.
        seeds["synthetic_no_panorama.yaml"] = re.sub(rb"(?m)^scene_panorama: .*$", b"scene_panorama: none", text)
        seeds["two_rooms.yaml"] = SYNTH_YAML
        # What the first runs found by hand: ratios whose photometry check_photometry refused.
        seeds["edge_gain_1e-300.yaml"] = SYNTH_YAML.replace(b"edge_gain: 0.25", b"edge_gain: 1e-300")
        seeds["exposure_1e-310.yaml"] = SYNTH_YAML.replace(b"fisheye_exposure: 0.5", b"fisheye_exposure: 1e-310")
    elif target == "capture":
        seeds["template_capture.txt"] = target_seed("capture", os.path.join(FUZZ_DIR, "capture.seed"))
        path = os.path.join(recording, "capture.txt")
        if os.path.isfile(path):
            seeds["synthetic_capture.txt"] = first_lines(path, INDEX_LINES)
    elif target == "photometric":
        seeds["template_photometric.yaml"] = target_seed("photometric", os.path.join(FUZZ_DIR, "photometric.seed"))
        path = os.path.join(recording, "calibration", "photometric.yaml")
        if os.path.isfile(path):
            seeds["synthetic_photometric.yaml"] = open(path, "rb").read()
    elif target == "board":
        seeds["board.yaml"] = BOARD_YAML
        seeds["boards.yaml"] = BOARDS_YAML
        path = os.path.join(recording, "calibration", "boards.yaml")
        if os.path.isfile(path):  # its board map; the views' corners after it are not read
            seeds["synthetic_boards.yaml"] = open(path, "rb").read().split(b"\nviews:")[0] + b"\n"
    elif target == "cli":  # argvs, NUL between arguments, of the options the target walks
        for name, argv in CLI_ARGVS.items():
            seeds[name] = b"\0".join(argv)
    elif target == "trajectory":
        for name in ("rgb_trajectory.txt", "fisheye_trajectory.txt"):
            path = os.path.join(recording, "groundtruth", name)
            if os.path.isfile(path):
                seeds["synthetic_" + name] = first_lines(path, INDEX_LINES)
        seeds["tum_comments.txt"] = b"# ground truth\n1.0 0 0 0 0 0 0 1\n\n2.5 0.1 -0.2 1e-3 0.7071 0 0 0.7071\n"
    elif target == "zip":
        for zip64 in (False, True):  # a small recording's text files, in a plain and a zip64 directory
            buffer = io.BytesIO()
            with zipfile.ZipFile(buffer, "w", zipfile.ZIP_DEFLATED) as z:
                for name in ("rig.yaml", "room.yaml", "rgb.txt"):
                    path = os.path.join(recording, name)
                    if os.path.isfile(path):
                        with z.open("living/" + name, "w", force_zip64=zip64) as f:
                            f.write(first_lines(path, INDEX_LINES))
                z.writestr("living/rgb/", b"")
            seeds[f"recording{'_zip64' if zip64 else ''}.zip"] = buffer.getvalue()
    if not seeds:
        sys.exit(f"fuzz: no seeds for {target} in {recording}")
    for name, data in seeds.items():
        with open(os.path.join(corpus, name), "wb") as f:
            f.write(data)


def ledger_add(target, execs, seconds, crashes, where):
    new = not os.path.isfile(LEDGER)
    os.makedirs(FUZZ_DIR, exist_ok=True)
    with open(LEDGER, "a") as f:
        if new:
            f.write(LEDGER_HEADER)
        stamp = datetime.datetime.now(datetime.timezone.utc).strftime("%Y-%m-%dT%H:%M:%SZ")
        f.write(f"{stamp}\t{target}\t{execs}\t{seconds:.0f}\t{crashes}\t{where}\n")


def ledger_totals():
    """Executions, seconds and crashes per target over every run the ledger holds."""
    totals = {t: [0, 0.0, 0] for t in TARGETS}
    if os.path.isfile(LEDGER):
        with open(LEDGER) as f:
            for line in f.read().splitlines()[1:]:
                fields = line.split("\t")
                if len(fields) >= 5 and fields[1] in totals:
                    totals[fields[1]][0] += int(fields[2])
                    totals[fields[1]][1] += float(fields[3])
                    totals[fields[1]][2] += int(fields[4])
    return totals


def print_ledger():
    totals = ledger_totals()
    for target, (execs, seconds, crashes) in totals.items():
        print(f"ledger {target}: {execs} executions in {seconds / 3600:.1f} h, {crashes} failing runs")
    print("ledger: " + " ".join(f"{t}={execs}" for t, (execs, _, _) in totals.items())
          + f" min_execs={min(execs for execs, _, _ in totals.values())}")


def add_logs(paths, where):
    """Counts libFuzzer logs of runs made elsewhere: the target is the log's name up to '_' or '.'."""
    for path in paths:
        target = re.split(r"[_.]", os.path.basename(path))[0]
        if target not in TARGETS:
            sys.exit(f"fuzz: {path}: its name does not start with a target ({', '.join(TARGETS)})")
        with open(path, errors="replace") as f:
            text = f.read()
        units = [int(m.group(1)) for m in map(EXECS.match, text.splitlines()) if m]
        took = [int(m.group(1)) for m in re.finditer(r"^Done \d+ runs in (\d+) second", text, re.M)]
        if not units:
            sys.exit(f"fuzz: {path}: no 'stat::number_of_executed_units' line (was -print_final_stats=1 given?)")
        crashed = int("==ERROR" in text or "broken invariant" in text or "SUMMARY:" in text)
        ledger_add(target, sum(units), sum(took), crashed, where)
        print(f"fuzz: {path}: {target} {sum(units)} executions counted ({where})")


# True for the short form: the targets are the normal build's replay programs, not libFuzzer's.
REPLAY = False


def binary(target):
    if REPLAY:
        return os.path.join(rp.BUILD, "tests", f"replay_{target}")
    return os.path.join(FUZZ_DIR, "bin", f"fuzz_{target}")


def run_target(target, runs, seconds):
    corpus = os.path.join(FUZZ_DIR, "corpus", target)
    if not os.path.isdir(corpus) or not os.listdir(corpus):
        make_corpus(target, corpus)
    crashes = os.path.join(FUZZ_DIR, "crashes", target)
    os.makedirs(crashes, exist_ok=True)
    before = set(os.listdir(crashes))
    cmd = [binary(target), corpus, f"-artifact_prefix={crashes}/", "-print_final_stats=1", "-timeout=20",
           "-rss_limit_mb=3072", f"-runs={runs}" if runs else "-runs=-1"]
    if seconds:
        cmd.append(f"-max_total_time={seconds}")
    if target in MAX_LEN:
        cmd.append(f"-max_len={MAX_LEN[target]}")
    # Each target writes its input to a file and loads it: in memory (/dev/shm) that runs 2 to 5
    # times faster than on disk.
    scratch = tempfile.mkdtemp(prefix="roomprobe-fuzz-", dir="/dev/shm" if os.access("/dev/shm", os.W_OK) else None)
    env = dict(os.environ, TMPDIR=scratch, ASAN_OPTIONS="detect_leaks=1:allocator_may_return_null=0",
               UBSAN_OPTIONS="halt_on_error=1:print_stacktrace=1",
               ASAN_SYMBOLIZER_PATH=shutil.which("llvm-symbolizer-21") or "")
    log_path = os.path.join(FUZZ_DIR, f"{target}.log")
    print(f"fuzz {target}: {' '.join(cmd)} (log {os.path.relpath(log_path, REPO)})", flush=True)
    start = time.monotonic()
    with open(log_path, "w") as log:
        result = subprocess.run(cmd, cwd=REPO, env=env, stdout=log, stderr=subprocess.STDOUT)
    elapsed = time.monotonic() - start
    shutil.rmtree(scratch, ignore_errors=True)
    execs = 0
    with open(log_path, errors="replace") as log:
        lines = log.read().splitlines()
    for line in lines:
        m = EXECS.match(line)
        if m:
            execs = int(m.group(1))
    found = sorted(set(os.listdir(crashes)) - before)
    # Ctrl-C (libFuzzer: "run interrupted", status 72) stops a run; it finds nothing.
    interrupted = any("libFuzzer: run interrupted" in line for line in lines) and not found
    failed = (result.returncode != 0 and not interrupted) or bool(found)
    if failed:
        start_at = next((i for i, line in enumerate(lines) if "ERROR: " in line or "broken invariant" in line), max(0, len(lines) - 30))
        print("\n".join(lines[start_at:start_at + 40]))
    print(f"fuzz {target}: {execs} executions in {elapsed:.0f} s ({execs / max(elapsed, 1e-9):.0f}/s), corpus {len(os.listdir(corpus))} inputs, "
          + (f"FAILED (status {result.returncode}); inputs kept: {', '.join(os.path.join(os.path.relpath(crashes, REPO), f) for f in found) or 'none'}"
             if failed else "no crash" + (" (interrupted)" if interrupted else "")), flush=True)
    ledger_add(target, execs, elapsed, int(failed), os.uname().nodename)
    return execs, (len(found) or 1) if failed else 0, elapsed


def replay_target(target):
    """The short form: build/tests/replay_TARGET (the normal build, no libFuzzer, no sanitizers) runs
    each input of the target's corpus and of its kept failures once. Returns (inputs, failed)."""
    corpus = os.path.join(FUZZ_DIR, "corpus", target)
    if not os.path.isdir(corpus) or not os.listdir(corpus):
        make_corpus(target, corpus)
    folders = [corpus] + [f for f in [os.path.join(FUZZ_DIR, "crashes", target)] if os.path.isdir(f) and os.listdir(f)]
    scratch = tempfile.mkdtemp(prefix="roomprobe-replay-", dir="/dev/shm" if os.access("/dev/shm", os.W_OK) else None)
    start = time.monotonic()
    try:
        result = subprocess.run([binary(target)] + folders, cwd=REPO, env=dict(os.environ, TMPDIR=scratch),
                                capture_output=True, text=True, errors="replace", timeout=REPLAY_TIMEOUT_S)
        returncode, out, err = result.returncode, result.stdout, result.stderr
    except subprocess.TimeoutExpired as e:
        returncode, out, err = "timeout", "", (e.stderr or b"").decode(errors="replace") if isinstance(e.stderr, bytes) else (e.stderr or "")
    finally:
        shutil.rmtree(scratch, ignore_errors=True)
    elapsed = time.monotonic() - start
    m = re.search(r"replayed (\d+) inputs", out)
    inputs = int(m.group(1)) if m else 0
    if returncode != 0 or m is None:
        named = [line for line in err.splitlines() if line.startswith("replay: ")]
        print("\n".join(err.splitlines()[-20:]))
        print(f"fuzz {target}: {inputs} executions in {elapsed:.1f} s (corpus replay), FAILED ({'a hang past ' + str(REPLAY_TIMEOUT_S) + ' s' if returncode == 'timeout' else f'status {returncode}'})"
              f" at {named[-1][len('replay: '):] if named else 'the start'}", flush=True)
        return inputs, True
    print(f"fuzz {target}: {inputs} executions in {elapsed:.1f} s (corpus replay: {', '.join(os.path.relpath(f, REPO) for f in folders)}), no crash", flush=True)
    return inputs, False


def main():
    ap = argparse.ArgumentParser(prog="./roomprobe fuzz", description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("target", nargs="?", choices=TARGETS + ["all"])
    ap.add_argument("--runs", type=int, default=0, help="executions per target (libFuzzer's -runs)")
    ap.add_argument("--seconds", type=int, default=0, help="time per target (libFuzzer's -max_total_time)")
    ap.add_argument("--ledger", action="store_true", help="print the executions of every run so far (build/fuzz/ledger.tsv) and stop")
    ap.add_argument("--add-logs", nargs="+", metavar="LOG", help="count libFuzzer logs (TARGET*.log) of runs made on another machine, and stop")
    ap.add_argument("--where", default="elsewhere", help="with --add-logs: the machine the logs come from")
    ap.add_argument("--replay", action="store_true",
                    help="the short form (the test suite's): each target's corpus and kept failures run once through "
                         "build/tests/replay_TARGET of the normal build (./roomprobe build); no libFuzzer, no sanitizers")
    opts = ap.parse_args()
    if opts.add_logs:
        add_logs(opts.add_logs, opts.where)
        print_ledger()
        return
    if opts.ledger:
        print_ledger()
        return
    if opts.target is None:
        ap.error("name a target, or all")
    if opts.replay:
        global REPLAY
        REPLAY = True
        targets = TARGETS if opts.target == "all" else [opts.target]
        results = [replay_target(target) for target in targets]
        failed = sum(1 for _, bad in results if bad)
        print(f"summary: targets={len(targets)} replayed={sum(n for n, _ in results)} failed={failed}")
        sys.exit(1 if failed else 0)
    if opts.runs < 0 or opts.seconds < 0 or (opts.runs == 0 and opts.seconds == 0):
        ap.error("give --runs N or --seconds S (or both), each > 0")
    build = subprocess.run(["scons", "-Q", f"-j{os.cpu_count() or 2}", "fuzz=yes"], cwd=REPO)
    if build.returncode != 0:
        sys.exit("fuzz: building the targets failed (scons fuzz=yes)")
    total_execs = total_crashes = 0
    total_seconds = 0.0
    targets = TARGETS if opts.target == "all" else [opts.target]
    for target in targets:
        execs, crashes, seconds = run_target(target, opts.runs, opts.seconds)
        total_execs += execs
        total_crashes += crashes
        total_seconds += seconds
    print_ledger()
    print(f"summary: targets={len(targets)} execs={total_execs} crashes={total_crashes} seconds={total_seconds:.0f}")
    sys.exit(1 if total_crashes else 0)


if __name__ == "__main__":
    main()
