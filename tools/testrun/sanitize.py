"""--sanitize: the sanitizer builds' folders, environments and reports, and the godot suite's sanitized project."""

import os
import re
import shlex

import rp_godot as rp

from . import common
from .common import EDITOR_BAD, IMPORT_TIMEOUT, fresh_project_copy, noise_note, show_with_context

# The first line of a sanitizer's report, and its last.
SANITIZER_START = re.compile(r"^(==\d+==)?(WARNING|ERROR): (Thread|Address|Leak)Sanitizer|: runtime error: ")
SANITIZER_SUMMARY = re.compile(r"^SUMMARY: \w+Sanitizer: .*$")
# halt_on_error: the first report ends the run (TSan exits with 66, ASan and UBSan with 1).
SANITIZER_ENV = {
    "thread": {"TSAN_OPTIONS": "halt_on_error=1 second_deadlock_stack=1"},
    # detect_leaks=0: OpenNI2's driver plugins leak their static objects and are unloaded before
    # LeakSanitizer looks, so their leaks can be neither named nor suppressed (the rest is leak-free).
    # The same holds in Godot, which loads the same drivers through our library; there Godot (not
    # instrumented, and not ours) also keeps allocations to exit, and unloads our library before
    # LeakSanitizer looks, so what it reported could not be told apart or named. Leaks of our code
    # are checked elsewhere: the core's by ./roomprobe soak --sanitize address (LeakSanitizer on),
    # objects left through the engine by the godot suite itself (ObjectDB, RIDs, orphan nodes).
    "address": {"ASAN_OPTIONS": "halt_on_error=1 detect_leaks=0", "UBSAN_OPTIONS": "halt_on_error=1 print_stacktrace=1"},
}
# Only in the godot suite's Godot. allow_user_segv_handler=0: Godot installs its own crash handler
# over ASan's; ASan's report of a bad access (its stack, the memory's history) is the one wanted.
# verify_asan_link_order=0: tests/sanitize/no_deepbind.c is preloaded before ASan's runtime (it must
# come first to replace dlopen), which ASan would otherwise refuse.
SANITIZER_GODOT_ENV = {"address": {"ASAN_OPTIONS": "allow_user_segv_handler=0 verify_asan_link_order=0"}}
# Only in the editor import before it: the editor (Godot 4.6.3's, stripped) takes two of its own
# mutexes in both orders, tens of thousands of lock-order reports with every frame in /usr/bin/godot,
# which a suppression could only name by the module, and so every stack (each has a Godot frame).
# The test run itself, where our code runs, keeps deadlock detection.
SANITIZER_IMPORT_ENV = {"thread": {"TSAN_OPTIONS": "detect_deadlocks=0"}}
TSAN_SUPPRESSIONS = os.path.join(rp.REPO, "tests", "tsan.supp")
# The sanitizer runtimes Godot needs in LD_PRELOAD to load a sanitized library (read from the
# library's DT_NEEDED): the runtime must be the first library in the process.
SANITIZER_RUNTIME = re.compile(r"\[(lib(asan|ubsan|tsan)\.so[.\d]*)\]")


def sanitized_build_dir(opts):
    """'' for the normal build/tests/; 'debug-tsan' or 'debug-asan' (SConstruct's build dir) with --sanitize."""
    if not opts.sanitize:
        return ""
    args = opts.scons_args if opts.scons_args is not None else os.environ.get("ROOMPROBE_SCONS_ARGS", "")
    target = "release" if "target=release" in shlex.split(args) else "debug"
    return f"{target}-{'tsan' if opts.sanitize == 'thread' else 'asan'}"


def sanitizer_env(opts, *extra):
    """TSAN_OPTIONS etc.: ours first (then those of the extra tables, e.g. SANITIZER_GODOT_ENV), then
    what the caller set, which wins where both set one."""
    env = {}
    for var, value in SANITIZER_ENV[opts.sanitize].items():
        if var == "TSAN_OPTIONS" and os.path.exists(TSAN_SUPPRESSIONS):
            value += f" suppressions={TSAN_SUPPRESSIONS}"
        for table in extra:
            if var in table.get(opts.sanitize, {}):
                value += " " + table[opts.sanitize][var]
        env[var] = f"{value} {os.environ.get(var, '')}".strip()
    return env


def sanitizer_env_text(opts, env=None):
    return " ".join(f"{k}={shlex.quote(v)}" for k, v in (env or sanitizer_env(opts)).items())


def sanitizer_report(lines):
    """(where the first sanitizer report in lines starts, that report through its SUMMARY line);
    (len(lines), []) when there is none."""
    for i, line in enumerate(lines):
        if SANITIZER_START.search(line):
            report = lines[i:]
            for j, rest in enumerate(report):
                if SANITIZER_SUMMARY.match(rest):
                    return i, report[:j + 1]
            return i, report
    return len(lines), []


def sanitizer_summary(report):
    """'ThreadSanitizer: data race file:line in function', or the report's first line."""
    return next((m.group(0)[len("SUMMARY: "):] for m in map(SANITIZER_SUMMARY.match, report) if m), report[0].strip())


def sanitized_project(opts, s):
    """(the scratch copy of the project that loads the sanitized libraries, imported; the environment
    Godot runs in), or (None, None) with a failure recorded in s.

    build/<target>-asan|tsan/godot_project: a fresh copy of godot_project/ without its libraries
    (fresh_project_copy, as the editor suite's), whose two .gdextension files name the sanitized
    library and the binding's test extension from build/<target>-asan|tsan/bin/ (linked into their
    bin/). Godot itself is not instrumented: the sanitizer's runtime goes in LD_PRELOAD, after
    tests/sanitize/no_deepbind.c's library; the tests find the repository through $ROOMPROBE_REPO
    (test_case.gd's repo_path). A report in the import fails the suite as one in the run does.
    """
    build = os.path.join(rp.BUILD, sanitized_build_dir(opts))
    target = sanitized_build_dir(opts).split("-")[0]
    libs = [os.path.join(build, "bin", f"{lib}.linux.{target}.x86_64.so") for lib in ("libroomprobe", "libroomprobe_binding_test")]
    missing = [lib for lib in libs if not os.path.isfile(lib)]
    if missing:
        s.fail(f"godot: no sanitized {', '.join(rp.relpath(m) for m in missing)} (scons sanitize={opts.sanitize} sanitize_godot=yes)")
        print(f"FAILED: {s.failures[-1]}")
        return None, None
    project = os.path.join(build, "godot_project")
    fresh_project_copy(project, leave_out=("*.so",))
    for gdextension, lib in zip(("addons/roomprobe/roomprobe.gdextension", "tests/binding/roomprobe_binding_test.gdextension"), libs):
        folder = os.path.dirname(gdextension)
        os.makedirs(os.path.join(project, folder, "bin"), exist_ok=True)
        os.symlink(lib, os.path.join(project, folder, "bin", os.path.basename(lib)))
        path = os.path.join(project, gdextension)
        with open(path) as f:
            text = f.read()
        # Every Linux entry (debug and release) names the one sanitized library.
        text, n = re.subn(r'^(linux\.\w+\.x86_64 = )"[^"]*"$', lambda m: f'{m.group(1)}"res://{folder}/bin/{os.path.basename(lib)}"', text, flags=re.M)
        if n == 0:
            s.fail(f"godot: {gdextension} names no linux.*.x86_64 library to replace")
            print(f"FAILED: {s.failures[-1]}")
            return None, None
        with open(path, "w") as f:
            f.write(text)
    # ROOMPROBE_SANITIZER: tests that pace a recording by the scene's clock slow it (test_case.gd's sanitizer()).
    env = dict(os.environ, **sanitizer_env(opts, SANITIZER_GODOT_ENV), ROOMPROBE_REPO=rp.REPO, ROOMPROBE_SANITIZER=opts.sanitize)
    runtimes = sanitizer_runtimes(libs[0])
    no_deepbind = os.path.join(build, "bin", "librp_no_deepbind.so")
    if not runtimes or not os.path.isfile(no_deepbind):
        s.fail(f"godot: {rp.relpath(libs[0])} needs no sanitizer runtime (built without sanitize=?)" if not runtimes else
               f"godot: no {rp.relpath(no_deepbind)} (scons sanitize={opts.sanitize} sanitize_godot=yes)")
        print(f"FAILED: {s.failures[-1]}")
        return None, None
    # Godot's GDExtension loader asks for RTLD_DEEPBIND, which the runtimes refuse: no_deepbind's
    # dlopen drops it, so it comes before them (tests/sanitize/no_deepbind.c).
    env["LD_PRELOAD"] = " ".join([no_deepbind] + runtimes + ([os.environ["LD_PRELOAD"]] if os.environ.get("LD_PRELOAD") else []))

    # The import, under the sanitizer too: the editor loads both libraries and writes .godot/.
    log = os.path.join(common.LOGS, "godot-import.log")
    s.logs.append(log)
    cmd = rp.import_command(project)
    import_env = dict(env, **sanitizer_env(opts, SANITIZER_GODOT_ENV, SANITIZER_IMPORT_ENV))
    rp.header(f"godot: import of the scratch copy: {shlex.join(cmd)} ({sanitizer_env_text(opts, godot_env_shown(import_env))})")
    r = rp.run(cmd, log, IMPORT_TIMEOUT * 4, env=import_env)
    s.seconds += r.seconds
    kept, dropped = rp.filter_noise(r.lines)
    start, report = sanitizer_report(kept)
    bad = [line for line in kept[:start] if EDITOR_BAD.search(line)]
    if report or r.rc != 0 or r.timed_out or bad:
        why = sanitizer_summary(report) if report else rp.describe_exit(r) if r.rc or r.timed_out else f"{len(bad)} error line(s)"
        s.fail(f"godot: the import of {rp.relpath(project)}: {why}")
        print(f"FAILED: the import: {why} ({rp.fmt_duration(r.seconds)}); see {rp.relpath(log)}")
        show_with_context(kept, bad)
        rp.tail(report or ([] if bad else kept), 80)
        return None, None
    print(f"ok ({rp.fmt_duration(r.seconds)}){noise_note(dropped)}")
    return project, env


def sanitizer_runtimes(library):
    """The sanitizer runtimes the library needs (readelf -d's NEEDED), ASan's first: it must be
    loaded before any other library that allocates (UBSan's runtime does)."""
    r = rp.run(["readelf", "-d", library])
    found = [m.group(1) for m in map(SANITIZER_RUNTIME.search, r.lines) if m and "(NEEDED)" in m.string]
    return sorted(found, key=lambda lib: not lib.startswith("libasan"))


def godot_env_shown(env):
    """The variables of env that the sanitized Godot run adds, for the header."""
    return {k: env[k] for k in ("LD_PRELOAD", "ASAN_OPTIONS", "UBSAN_OPTIONS", "TSAN_OPTIONS", "ROOMPROBE_REPO", "ROOMPROBE_SANITIZER") if k in env}
