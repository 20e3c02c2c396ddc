"""Reliability of the parallel verbs: Ray faults (a silent address, SIGTERM, SIGKILL) end
cleanly and a Ray instance started here is its own; huge ``--episodes`` start at once in
flat memory; Ctrl-C, a closed pipe and a bad ``--domain=VALUE`` end without a traceback.
(Local against Ray results: ``test_ray``.)"""

from __future__ import annotations

import os
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest
from ports import closed_port

from osg_control import cli
from osg_control.errors import EXIT_CODES, BackendError
from osg_control.parallel import open_executor
from osg_control.parallel.processes import descendants

ray = pytest.importorskip("ray")
ROOT = Path(__file__).resolve().parents[1]
SKILL = "move-home-to-door"
LINUX = pytest.mark.skipif(not sys.platform.startswith("linux"), reason="reads /proc")


class _SilentServer:
    """A TCP server on 127.0.0.1 that accepts connections and never answers."""

    def __init__(self) -> None:
        self.sock = socket.create_server(("127.0.0.1", 0))
        self.port = int(self.sock.getsockname()[1])
        self.held: list[socket.socket] = []
        threading.Thread(target=self._accept, daemon=True).start()

    def _accept(self) -> None:
        while True:
            try:
                self.held.append(self.sock.accept()[0])
            except OSError:
                return

    def close(self) -> None:
        for conn in self.held:
            conn.close()
        self.sock.close()


@pytest.mark.slow
@pytest.mark.parametrize("form", ["127.0.0.1:{port}", "ray://127.0.0.1:{port}"])
def test_a_silent_address_is_an_error_naming_it_within_seconds(form: str) -> None:
    server = _SilentServer()
    address = form.format(port=server.port)
    started = time.monotonic()
    try:
        with pytest.raises(BackendError, match=f"'{address}' accepts connections but did not"):
            with open_executor("ray", 1, address):
                pass
    finally:
        server.close()
    assert time.monotonic() - started < 20


@pytest.mark.slow
def test_the_cli_names_a_silent_address(capsys) -> None:
    server = _SilentServer()
    address = f"127.0.0.1:{server.port}"
    try:
        argv = ["collect", "--skill", SKILL, "--episodes", "1", "--backend", "ray"]
        assert cli.main([*argv, "--address", address]) == EXIT_CODES["failure"]
    finally:
        server.close()
    err = capsys.readouterr().err
    assert address in err and "did not answer" in err and "Traceback" not in err


@pytest.mark.slow
def test_a_ray_instance_started_here_ignores_ray_address(monkeypatch) -> None:
    """Without ``--address`` osg starts its own instance (the one its watchdog ends), even
    where ``RAY_ADDRESS`` names another cluster, which Ray would otherwise join."""
    closed = f"127.0.0.1:{closed_port()}"
    monkeypatch.setenv("RAY_ADDRESS", closed)
    assert not ray.is_initialized()
    with open_executor("ray", 1) as executor:
        assert list(executor.map(abs, [-1, -2, 3])) == [1, 2, 3]
        assert ray.get_runtime_context().gcs_address != closed
    assert not ray.is_initialized()


def _env(tmp_path: Path, **extra: str) -> dict[str, str]:
    return {**os.environ, "OSG_CACHE_DIR": str(tmp_path), "PYTHONPATH": str(ROOT), **extra}


def _osg(argv: list[str], env: dict[str, str], **kwargs) -> subprocess.Popen:
    command = [sys.executable, "-m", "osg_control.cli", *argv]
    return subprocess.Popen(command, env=env, text=True, **kwargs)


def _wait_for_chunk(parts: Path, proc: subprocess.Popen, seconds: float = 90) -> None:
    deadline = time.monotonic() + seconds
    while not list(parts.rglob("*.h5")) and time.monotonic() < deadline:
        assert proc.poll() is None, "osg ended before its first chunk"
        time.sleep(0.1)
    assert list(parts.rglob("*.h5")), "no chunk was written"


@pytest.mark.slow
def test_sigterm_during_a_ray_collect_exits_130(tmp_path: Path) -> None:
    argv = ["collect", "--skill", SKILL, "--episodes", "5000", "--workers", "1"]
    argv += ["--backend", "ray", "--out", str(tmp_path / "data")]
    proc = _osg(argv, _env(tmp_path), stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        _wait_for_chunk(tmp_path / "data" / ".parts", proc)
        proc.send_signal(signal.SIGTERM)
        _out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == EXIT_CODES["interrupted"], err
    assert "osg: interrupted" in err and "Traceback" not in err


def _marked(mark: str) -> list[str]:
    """Live processes whose environment carries ``OSG_TEST_MARK=mark`` (their titles)."""
    found = []
    for entry in Path("/proc").iterdir():
        if entry.name.isdigit() and int(entry.name) != os.getpid():
            try:
                marked = f"OSG_TEST_MARK={mark}".encode() in (entry / "environ").read_bytes()
                state = (entry / "stat").read_text().rsplit(")", 1)[1].split()[0]
                title = (entry / "cmdline").read_bytes().split(b"\0")[0].decode()
            except OSError:
                continue
            if marked and state != "Z":
                found.append(f"{entry.name} {title}")
    return found


@pytest.mark.slow
@LINUX
def test_a_sigkilled_ray_collect_leaves_no_ray_process(tmp_path: Path) -> None:
    mark = f"{os.getpid()}-{time.time_ns()}"
    argv = ["collect", "--skill", SKILL, "--episodes", "5000", "--workers", "1"]
    argv += ["--backend", "ray", "--out", str(tmp_path / "data")]
    env = _env(tmp_path, OSG_TEST_MARK=mark)  # every process osg starts inherits it
    proc = _osg(argv, env, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    try:
        _wait_for_chunk(tmp_path / "data" / ".parts", proc)
        time.sleep(3)  # Ray's agents are up by now
        assert len(_marked(mark)) > 3, "Ray's processes were not seen"
        proc.kill()
        proc.wait(timeout=10)
        deadline = time.monotonic() + 15
        while _marked(mark) and time.monotonic() < deadline:
            time.sleep(0.5)
        left = _marked(mark)
        assert not left, f"Ray processes outlived a SIGKILLed osg: {left}"
    finally:
        proc.kill()
        for entry in _marked(mark):
            os.kill(int(entry.split()[0]), signal.SIGKILL)


def _tree_rss_kb(pid: int) -> int:
    """The resident memory of ``pid`` and its descendants, kB (from /proc)."""
    total = 0
    for member in [pid, *(child for child, _start in descendants(pid))]:
        try:
            status = Path(f"/proc/{member}/status").read_text()
        except OSError:  # gone meanwhile
            continue
        fields = dict(line.split(":", 1) for line in status.splitlines() if ":" in line)
        total += int(fields.get("VmRSS", "0 kB").split()[0])
    return total


HUGE = "1000000000"
COLLECT_HUGE = f"""
import sys
from osg_control.commands.errors import handle_errors
from osg_control.data.collect import collect_skill
from osg_control.domain.registry import get_domain
from osg_control.parallel import LocalExecutor
with handle_errors() as outcome:
    collect_skill(get_domain("kitchen"), {SKILL!r}, {HUGE}, 0, sys.argv[1], LocalExecutor(2))
sys.exit(outcome.code)
"""
"""``osg collect --episodes 1e9`` is refused for its disk space (tens of TB), so the
collector itself is run (what the verb calls) to show its jobs are made lazily."""
HUGE_RUNS = {
    "collect": ["-c", COLLECT_HUGE],
    "evaluate tasks": ["-m", "osg_control.cli", "evaluate", "tasks", "--episodes", HUGE],
    "eval-skills": ["-m", "osg_control.cli", "eval-skills", "--episodes", HUGE, "--skill", SKILL],
    "classifier reach": ["-m", "osg_control.cli", "classifier", "reach", "--episodes", HUGE],
}
RSS_LIMIT_KB = 1_500_000


@pytest.mark.slow
@LINUX
@pytest.mark.parametrize("verb", list(HUGE_RUNS))
def test_a_billion_episodes_start_at_once_in_flat_memory(verb: str, tmp_path: Path) -> None:
    command = [sys.executable, *HUGE_RUNS[verb]]
    command += [str(tmp_path / "data")] if verb == "collect" else ["--workers", "2"]
    proc = subprocess.Popen(
        command, env=_env(tmp_path), text=True, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE
    )
    lines: list[str] = []
    reader = threading.Thread(target=lambda: lines.extend(iter(proc.stderr.readline, "")))
    reader.start()
    try:
        started = time.monotonic()
        while "ep/s" not in "".join(lines):  # tqdm's first line: "0/1000000000 [..., ?ep/s]"
            assert proc.poll() is None, "".join(lines)
            assert time.monotonic() - started < 30, f"no progress line in 30 s: {lines}"
            time.sleep(0.1)
        peak = 0
        for _ in range(30):  # 6 s of work, sampled
            peak = max(peak, _tree_rss_kb(proc.pid))
            time.sleep(0.2)
        assert peak < RSS_LIMIT_KB, f"{peak} kB resident"
        proc.send_signal(signal.SIGINT)
        try:
            proc.wait(timeout=60)
        except subprocess.TimeoutExpired:
            proc.kill()
            reader.join(timeout=10)
            pytest.fail("no exit within 60 s of SIGINT; its stderr:\n" + "".join(lines)[-4000:])
    finally:
        proc.kill()
        reader.join(timeout=10)
    err = "".join(lines)
    assert proc.returncode == EXIT_CODES["interrupted"], err
    assert "Traceback" not in err


@pytest.mark.slow
@LINUX
def test_ctrl_c_on_a_pool_collect_prints_no_traceback(tmp_path: Path) -> None:
    argv = ["collect", "--skill", SKILL, "--episodes", "5000", "--workers", "2"]
    argv += ["--out", str(tmp_path / "data")]
    proc = _osg(
        argv,
        _env(tmp_path),
        stdout=subprocess.DEVNULL,
        stderr=subprocess.PIPE,
        start_new_session=True,  # its own process group, as a terminal's foreground job
    )
    try:
        _wait_for_chunk(tmp_path / "data" / ".parts", proc)
        os.killpg(proc.pid, signal.SIGINT)  # what Ctrl-C does: the whole group
        _out, err = proc.communicate(timeout=60)
    finally:
        proc.kill()
    assert proc.returncode == EXIT_CODES["interrupted"], err
    assert "osg: interrupted" in err and "Traceback" not in err, err
    assert "KeyboardInterrupt" not in err


@pytest.mark.slow
@pytest.mark.parametrize("argv", [["domains"], ["domains", "--json"], ["--help"]])
def test_a_closed_stdout_ends_quietly(argv: list[str], tmp_path: Path) -> None:
    proc = _osg(argv, _env(tmp_path), stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    proc.stdout.close()  # `osg ... | head` once head has gone
    err = proc.stderr.read()
    proc.wait(timeout=60)
    assert err == "", err
    assert proc.returncode in (EXIT_CODES["success"], EXIT_CODES["failure"])


def test_a_broken_pipe_elsewhere_is_still_reported(capsys, monkeypatch) -> None:
    def broken(_args: object) -> int:
        raise BrokenPipeError(32, "Broken pipe")  # e.g. a worker's pipe, stdout still open

    parser = cli.build_parser()
    original = parser.parse_args

    def parse(argv: list[str]) -> object:
        args = original(argv)
        args.func = broken
        return args

    monkeypatch.setattr(cli, "build_parser", lambda modules=None: parser)
    monkeypatch.setattr(parser, "parse_args", parse)
    assert cli.main(["graph"]) == EXIT_CODES["failure"]
    assert "osg: error: broken pipe" in capsys.readouterr().err


@pytest.mark.parametrize(
    "argv",
    [["--domain=nope", "domains"], ["--domain", "nope", "domains"], ["domains", "--domain=nope"]],
)
def test_an_unknown_domain_is_refused_in_either_form(argv: list[str], capsys) -> None:
    assert cli.main(argv) == EXIT_CODES["usage"]
    err = capsys.readouterr().err
    assert "--domain" in err and "'nope'" in err and "kitchen" in err
