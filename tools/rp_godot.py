"""Helpers shared by tools/run_tests.py (tools/testrun/) and tools/run_demo.py (python3 standard library only).

Both scripts run inside RoomProbe's toolchain (./roomprobe test, ./roomprobe demo), from any
directory; paths here are absolute, from the repository root.
"""

import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import threading
import time

REPO = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
PROJECT = os.path.join(REPO, "godot_project")
BUILD = os.path.join(REPO, "build")

# Xvfb's screen for the rendering runs (the demo screenshot has its own size).
XVFB_SCREEN = "-screen 0 640x480x24"

_ANSI = re.compile(r"\x1b\[[0-9;?]*[A-Za-z]")

# Noise on machines without a sound card, never a sign of a problem here: ALSA's complaints
# when Godot probes audio, after which it falls back to the dummy driver. Every Godot run
# here passes --audio-driver Dummy, so these appear only if that is dropped.
# (Seen with Godot 4.6.3 under xvfb-run in the Debian sid toolchain.)
NOISE = [
    re.compile(r"^ALSA lib "),
    re.compile(r"^WARNING: All audio drivers failed, falling back to the dummy driver\."),
    re.compile(r"^\s+at: initialize \(servers/(audio/)?audio_server\.cpp:\d+\)"),
]
# An error line that is noise only when the "at:" line after it names the ALSA driver.
NOISE_PAIRS = [
    (re.compile(r"^ERROR: Condition \"status < 0\" is true\. Returning: ERR_CANT_OPEN\s*$"),
     re.compile(r"^\s+at: init_output_device \(drivers/alsa/")),
    # The headless editor saving any scene (even an empty Node3D): its thumbnail reads a texture
    # the dummy renderer does not have (Godot 4.6.3; editor::scene-roundtrip).
    (re.compile(r'^ERROR: Parameter "t" is null\.\s*$'),
     re.compile(r"^\s+at: texture_2d_get \(\./servers/rendering/dummy/storage/texture_storage\.h:")),
]


def strip_ansi(text):
    return _ANSI.sub("", text)


def filter_noise(lines):
    """lines without the known noise (see NOISE); returns (kept, dropped)."""
    kept, dropped = [], []
    i = 0
    while i < len(lines):
        line = lines[i]
        nxt = lines[i + 1] if i + 1 < len(lines) else ""
        if any(first.search(line) and second.search(nxt) for first, second in NOISE_PAIRS):
            dropped += [line, nxt]
            i += 2
            continue
        (dropped if any(p.search(line) for p in NOISE) else kept).append(line)
        i += 1
    return kept, dropped


def godot():
    """The Godot binary: $ROOMPROBE_GODOT, else godot on PATH."""
    return os.environ.get("ROOMPROBE_GODOT") or "godot"


def jobs():
    j = os.environ.get("ROOMPROBE_JOBS") or ""
    return int(j) if j.isdigit() and int(j) > 0 else (os.cpu_count() or 2)


def scons_command(default_args, override=None):
    """scons with default_args, or with the arguments in override / $ROOMPROBE_SCONS_ARGS."""
    args = override if override is not None else os.environ.get("ROOMPROBE_SCONS_ARGS")
    if args is not None:
        return ["scons"] + shlex.split(args)
    return ["scons", f"-j{jobs()}"] + list(default_args)


def have(program):
    return shutil.which(program) is not None


def fmt_duration(seconds):
    return f"{seconds:.1f} s" if seconds < 120 else f"{int(seconds // 60)} min {int(seconds % 60)} s"


def header(title):
    print(f"\n=== {title}", flush=True)


def relpath(path):
    try:
        return os.path.relpath(path)
    except ValueError:
        return path


class NoiseFilter:
    """filter_noise() for a stream: feed(line) returns the lines to show now; flush() the rest."""

    def __init__(self):
        self._held = None  # a line that is noise only if the next line says so

    def feed(self, line):
        out = []
        if self._held is not None:
            held, self._held = self._held, None
            if any(first.search(held) and second.search(line) for first, second in NOISE_PAIRS):
                return out
            out.append(held)
        if any(first.search(line) for first, _ in NOISE_PAIRS):
            self._held = line
        elif not any(p.search(line) for p in NOISE):
            out.append(line)
        return out

    def flush(self):
        held, self._held = self._held, None
        return [] if held is None else [held]


def describe_exit(result):
    """'exit status N', 'killed by SIGSEGV', 'timed out' or why it could not start."""
    if result.error:
        return f"could not start: {result.error}"
    if result.timed_out:
        return "timed out"
    if result.rc < 0:
        try:
            return f"killed by {signal.Signals(-result.rc).name}"
        except ValueError:
            return f"killed by signal {-result.rc}"
    return f"exit status {result.rc}"


class Result:
    """What run() saw: exit status, the output lines (ANSI codes stripped), the time taken."""

    def __init__(self, rc, lines, seconds, timed_out, error=None):
        self.rc = rc
        self.lines = lines
        self.seconds = seconds
        self.timed_out = timed_out
        self.error = error  # the OSError text when the program could not be started


def run(cmd, log_path=None, timeout=None, echo=None, cwd=REPO, env=None):
    """Runs cmd with stdout and stderr merged, line by line.

    Every line goes to log_path (when given); echo(line) is called for each line as it comes
    (ANSI codes stripped) so that callers can show progress. After timeout seconds the
    whole process group (cmd and its children, e.g. Xvfb under xvfb-run) is killed.
    """
    if log_path:
        os.makedirs(os.path.dirname(log_path), exist_ok=True)
    log = open(log_path, "w", encoding="utf-8", errors="replace") if log_path else None
    start = time.monotonic()
    if log:
        log.write("$ " + shlex.join(cmd) + "\n")
        log.flush()
    try:
        proc = subprocess.Popen(cmd, cwd=cwd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                                stdin=subprocess.DEVNULL, start_new_session=True)
    except OSError as e:
        if log:
            log.write(f"cannot run {cmd[0]}: {e}\n")
            log.close()
        return Result(127, [], time.monotonic() - start, False, error=str(e))

    timed_out = threading.Event()

    def kill_group():
        timed_out.set()
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except ProcessLookupError:
            pass

    timer = threading.Timer(timeout, kill_group) if timeout else None
    if timer:
        timer.daemon = True
        timer.start()
    lines = []
    try:
        for raw in proc.stdout:
            line = strip_ansi(raw.decode("utf-8", errors="replace")).rstrip("\r\n")
            lines.append(line)
            if log:
                log.write(line + "\n")
                log.flush()
            if echo:
                echo(line)
        rc = proc.wait()
    except KeyboardInterrupt:
        try:
            os.killpg(proc.pid, signal.SIGTERM)
        except ProcessLookupError:
            pass
        proc.wait()
        raise
    finally:
        if timer:
            timer.cancel()
        # Children that outlive the main process (a stray Xvfb) go with the group.
        try:
            os.killpg(proc.pid, signal.SIGKILL)
        except (ProcessLookupError, PermissionError):
            pass
    seconds = time.monotonic() - start
    if log:
        log.write(f"# exit status {rc}{' (timed out)' if timed_out.is_set() else ''}, {seconds:.1f} s\n")
        log.close()
    return Result(rc, lines, seconds, timed_out.is_set())


def godot_base_args(rendering=False, project=PROJECT):
    """Arguments every Godot run gets: the project, no audio (no ALSA noise), and for
    rendering runs Vulkan (the project's Forward+ renderer; lavapipe under Xvfb)."""
    args = [godot(), "--path", project, "--audio-driver", "Dummy"]
    if rendering:
        args += ["--rendering-driver", "vulkan"]
    else:
        args.insert(1, "--headless")
    return args


def xvfb_prefix(screen=XVFB_SCREEN):
    return ["xvfb-run", "-a", "-s", screen]


def project_extensions(project):
    """The project's .gdextension files as res:// paths, symlinked folders included."""
    found = []
    for d, dirs, files in os.walk(project, followlinks=True):
        dirs[:] = sorted(x for x in dirs if x != ".godot")
        for name in sorted(files):
            if name.endswith(".gdextension"):
                found.append("res://" + os.path.relpath(os.path.join(d, name), project).replace(os.sep, "/"))
    return found


def import_command(project=PROJECT):
    """The editor import: generates godot_project/.godot/ (class cache, import data).

    When the editor finds a GDExtension during its first scan, it loads it at run time and
    generates its class docs on a thread; quitting while that runs crashes Godot 4.5/4.6 on
    exit (upstream godotengine/godot#111048), and how long it runs depends on the machine.
    So .godot/extension_list.cfg, the list the editor itself writes after that scan, is
    written first when it lacks an extension: the editor then loads every extension at start-up,
    the path every later run takes, and `--editor --quit` is safe.
    """
    listed_path = os.path.join(project, ".godot", "extension_list.cfg")
    wanted = project_extensions(project)
    listed = []
    if os.path.exists(listed_path):
        with open(listed_path) as f:
            listed = [line.strip() for line in f if line.strip()]
    if set(wanted) - set(listed):
        os.makedirs(os.path.dirname(listed_path), exist_ok=True)
        with open(listed_path, "w") as f:
            f.write("".join(p + "\n" for p in wanted))
    return [godot(), "--headless", "--editor", "--quit", "--path", project]


def tail(lines, n=40, indent="    "):
    for line in lines[-n:]:
        print(indent + line)


def sconstruct_missing():
    return not os.path.exists(os.path.join(REPO, "SConstruct"))


def die(msg, code=1):
    print(msg, file=sys.stderr)
    sys.exit(code)
