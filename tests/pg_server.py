"""A throw-away PostgreSQL server that the tests start themselves (issue 18).

The store runs on PostgreSQL; its tests need a real server, and they must not depend on one being set
up beforehand (a developer's laptop, a fresh CI machine): so every test session runs `initdb` into a
temporary directory and starts its own server on a free port of 127.0.0.1, and tests that stop,
restart or crash the database get a server of their own. Nothing outside the temporary directory is
touched: the server listens only on the loopback address, its unix socket lives in its data directory
(no /var/run/postgresql), and removing the directory removes everything.

Why the postmaster is started as our own child (`postgres -D ...`) rather than by `pg_ctl start`:
`pg_ctl` hands the postmaster over to PID 1, and a container's PID 1 often reaps nobody, so every
stopped or killed server would stay in the process table as a zombie, and a zombie postmaster's pid
makes the next start of the same data directory refuse ("lock file already exists"). As our child it
is reaped by us, always. `pg_ctl` still does the orderly stop (`stop(mode)`).

`initdb` and `postgres` refuse to run as root. Under root (CI machines, containers) the server
binaries run as an unprivileged user — `postgres`, which Debian's package creates, else `nobody` —
through `subprocess`'s own `user=`/`group=` (a set*id in the child right before exec, as `setpriv`
does: no PAM session, no extra process between us and the postmaster), on a data directory chowned to
that user under a 0o755 directory of /tmp it can reach. The database superuser is always `hil`
(`initdb -U hil`), so URLs do not depend on who runs the tests.

Every blocking step has a timeout and fails with `PostgresError`, quoting the server's log.
"""

from __future__ import annotations

import atexit
import contextlib
import os
import pwd
import re
import shutil
import signal
import socket
import subprocess
import tempfile
import time
from pathlib import Path
from types import TracebackType
from typing import Any, Literal
from urllib.parse import quote

import psycopg
from psycopg import sql

from tests.proc_tree import descendants, wait_gone

BINARIES = ("initdb", "pg_ctl", "postgres")
SUPERUSER = "hil"
HOST = "127.0.0.1"

StopMode = Literal["smart", "fast", "immediate"]


class PostgresError(RuntimeError):
    """The test server could not be initialised, started, stopped or reached."""


def _holds_binaries(directory: Path) -> bool:
    return all(os.access(directory / name, os.X_OK) for name in BINARIES)


def _version_key(bin_dir: Path) -> tuple[int, ...]:
    """Sort key of /usr/lib/postgresql/<version>/bin: "15" < "16", "9.6" < "10"."""
    return tuple(int(part) for part in re.findall(r"\d+", bin_dir.parent.name))


def find_binaries() -> Path | None:
    """The directory holding `initdb`, `pg_ctl` and `postgres`, or None when PostgreSQL is missing.

    PATH first (a developer's own build, Homebrew, a distribution that puts them on PATH); then the
    highest version under /usr/lib/postgresql/*/bin, where Debian and Ubuntu install the server and
    leave it off PATH. A PATH entry that is a symlink (e.g. /usr/local/bin/initdb -> the Debian
    directory) counts by its target too, since pg_ctl finds `postgres` next to its real self.
    """
    found = shutil.which("initdb")
    if found is not None:
        for directory in (Path(found).parent, Path(found).resolve().parent):
            if _holds_binaries(directory):
                return directory
    debian = [d for d in Path("/usr/lib/postgresql").glob("*/bin") if _holds_binaries(d)]
    return max(debian, key=_version_key) if debian else None


def free_port() -> int:
    """A TCP port of 127.0.0.1 that nobody listens on right now (the kernel's pick).

    There is a window between closing this socket and the postmaster binding the port; `start()`
    retries with another port if someone took it meanwhile.
    """
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.bind((HOST, 0))
        return int(s.getsockname()[1])


def _server_user() -> pwd.struct_passwd | None:
    """Who runs the server binaries: None (ourselves) unless we are root, whom initdb refuses."""
    if os.geteuid() != 0:
        return None
    for name in ("postgres", "nobody"):
        with contextlib.suppress(KeyError):
            return pwd.getpwnam(name)
    raise PostgresError("running as root, and neither a 'postgres' nor a 'nobody' user exists to run "
                        "PostgreSQL as (initdb and postgres refuse root)")


class PostgresServer:
    """One PostgreSQL server in its own temporary directory, on 127.0.0.1 at a free port.

    `start()` initialises the data directory on first use and starts the server; `stop()` and
    `start()` again restart it on the same data and port (URLs stay valid); `kill()` crashes it;
    `close()` (or leaving the `with` block) stops it and removes the directory.

    `fast=True` (for tests) turns off `fsync` and `full_page_writes`: they only protect against an
    operating-system crash or power cut, which tests never cause, so a killed server still recovers
    every committed transaction. `synchronous_commit` stays on even then: turned off, a transaction
    reported committed can be lost when the server is killed within the next few hundred ms — exactly
    what the crash tests check must not happen — and with `fsync` off it would save only a `write()`
    per commit. `fast=False` keeps PostgreSQL's durable defaults, for benchmarks of commit latency.
    """

    def __init__(self, binaries: Path | None = None, *, fast: bool = True, max_connections: int = 200,
                 timeout: float = 30.0) -> None:
        """No I/O here: nothing happens until `start()`.

        `binaries`: the directory of initdb/pg_ctl/postgres (default: `find_binaries()`).
        `timeout`: the bound, in seconds, of each step (initdb, start, stop).
        """
        if max_connections < 100:
            raise ValueError(f"max_connections must be at least 100, got {max_connections}")
        self._binaries = binaries
        self.fast = fast
        self.max_connections = max_connections
        self.timeout = timeout
        self._base: Path | None = None  # the temporary directory: data/ and postgres.log
        self._port: int | None = None
        self._proc: subprocess.Popen[bytes] | None = None
        self._user: pwd.struct_passwd | None = None  # who runs the server binaries, found by _initdb

    # -- what the tests use -------------------------------------------------------------------------

    @property
    def port(self) -> int:
        """The TCP port on 127.0.0.1; fixed at the first start and kept across restarts."""
        if self._port is None:
            raise PostgresError("the server has not been started yet: no port")
        return self._port

    @property
    def data_dir(self) -> Path:
        return self._require_base() / "data"

    @property
    def log_path(self) -> Path:
        return self._require_base() / "postgres.log"

    @property
    def pid(self) -> int | None:
        """The postmaster's pid while it runs, else None."""
        return self._proc.pid if self.running and self._proc is not None else None

    @property
    def running(self) -> bool:
        return self._proc is not None and self._proc.poll() is None

    def url(self, dbname: str = "postgres") -> str:
        """`postgresql://hil@127.0.0.1:PORT/DBNAME` (trust authentication: no password; the name
        percent-encoded, so that any name CREATE DATABASE accepts makes a valid URL)."""
        return f"postgresql://{SUPERUSER}@{HOST}:{self.port}/{quote(dbname, safe='')}"

    def connect(self, dbname: str = "postgres", **kwargs: Any) -> psycopg.Connection[Any]:
        """A psycopg connection to `dbname`, with a connect timeout."""
        kwargs.setdefault("connect_timeout", max(2, round(self.timeout)))
        return psycopg.connect(self.url(dbname), **kwargs)

    def create_database(self, name: str, template: str | None = None) -> str:
        """CREATE DATABASE `name` (quoted as an identifier), a copy of `template` if given (a file-level
        copy: milliseconds, for a test's own copy of a prepared store); returns its URL."""
        statement = sql.SQL("CREATE DATABASE {}").format(sql.Identifier(name))
        if template is not None:
            statement = sql.SQL("CREATE DATABASE {} TEMPLATE {}").format(sql.Identifier(name),
                                                                          sql.Identifier(template))
        with self.connect(autocommit=True) as conn:
            conn.execute(statement)
        return self.url(name)

    # -- life cycle ---------------------------------------------------------------------------------

    def start(self) -> None:
        """Initialise the data directory if need be, start the server, wait until it accepts connections.

        The first start picks a free port (and another if that one is taken by the time the server
        binds it); later starts reuse it, so URLs handed out before a stop or a kill stay valid.
        """
        if self.running:
            raise PostgresError(f"the server is already running (pid {self.pid})")
        if self._base is None:
            self._initdb()
        if self._port is not None:
            self._launch(self._port)
            return
        for attempt in range(5):
            port = free_port()
            try:
                self._launch(port)
            except PostgresError:
                if attempt < 4 and "already in use" in self._log_tail():
                    continue
                raise
            self._port = port
            return

    def stop(self, mode: StopMode = "fast") -> None:
        """Stop the server with `pg_ctl stop -m MODE` and wait until it has gone.

        "smart" waits for clients to disconnect, "fast" disconnects them (what a service manager
        does), "immediate" stops without a checkpoint, like a crash as far as the data are concerned.
        """
        if not self.running or self._proc is None:
            return
        result = self._run([self._bin("pg_ctl"), "stop", "-D", str(self.data_dir), "-m", mode, "-w",
                            "-t", str(max(1, round(self.timeout)))], timeout=self.timeout + 10)
        if result.returncode != 0:
            raise PostgresError(f"pg_ctl stop -m {mode} failed ({result.returncode}): "
                                f"{result.stdout.strip()}\n{self._log_tail()}")
        try:
            self._proc.wait(timeout=self.timeout)
        except subprocess.TimeoutExpired as e:
            raise PostgresError(f"the postmaster (pid {self._proc.pid}) outlived `pg_ctl stop`") from e

    def kill(self) -> None:
        """Crash the server: SIGKILL to the postmaster and to every server process; nothing cleans up.

        The next `start()` runs crash recovery from the WAL. The server's other processes are killed
        too (each leads a process group of its own, so one by one, the postmaster first stopped so
        that it forks no more): left to notice their postmaster's death, a backend busy with a query
        would live on for as long as the query runs, holding the shared memory the next start needs.
        """
        if not self.running or self._proc is None:
            return
        pid = self._proc.pid
        os.kill(pid, signal.SIGSTOP)
        children = descendants(pid)
        os.kill(pid, signal.SIGKILL)
        for child in children:
            with contextlib.suppress(ProcessLookupError):
                os.kill(child, signal.SIGKILL)
        try:
            self._proc.wait(timeout=self.timeout)
        except subprocess.TimeoutExpired as e:
            raise PostgresError(f"the postmaster (pid {pid}) survived SIGKILL") from e
        if left := wait_gone(children, self.timeout):
            raise PostgresError(f"server processes {sorted(left)} survived SIGKILL")

    def close(self) -> None:
        """Stop the server if it runs (fast, else killed) and remove its temporary directory."""
        try:
            if self.running:
                try:
                    self.stop("fast")
                except PostgresError:
                    self.kill()
        finally:
            atexit.unregister(self.close)
            if self._base is not None:
                shutil.rmtree(self._base, ignore_errors=True)
                self._base = self._port = None  # a later start() begins afresh

    def __enter__(self) -> PostgresServer:
        self.start()
        return self

    def __exit__(self, exc_type: type[BaseException] | None, exc: BaseException | None,
                 tb: TracebackType | None) -> None:
        self.close()

    # -- inside -------------------------------------------------------------------------------------

    def _require_base(self) -> Path:
        if self._base is None:
            raise PostgresError("the server has no data directory (not started yet, or closed)")
        return self._base

    def _bin(self, name: str) -> str:
        if self._binaries is None:
            self._binaries = find_binaries()
            if self._binaries is None:
                raise PostgresError("PostgreSQL server binaries (initdb, pg_ctl, postgres) not found on "
                                    "PATH nor under /usr/lib/postgresql/*/bin")
        return str(self._binaries / name)

    def _env(self) -> dict[str, str]:
        """Our environment without libpq's PG* variables (a developer's PGHOST or PGDATA must not
        steer initdb or pg_ctl elsewhere), in the C locale so that the log is plain English."""
        env = {k: v for k, v in os.environ.items() if not k.startswith("PG")}
        env["LC_ALL"] = "C"
        if self._user is not None:
            env.update(HOME=self._user.pw_dir, USER=self._user.pw_name, LOGNAME=self._user.pw_name)
        return env

    def _as_user(self) -> dict[str, Any]:
        """Popen arguments that drop root for the server binaries (see the module's docstring)."""
        if self._user is None:
            return {}
        return {"user": self._user.pw_uid, "group": self._user.pw_gid, "extra_groups": []}

    def _run(self, args: list[str], timeout: float) -> subprocess.CompletedProcess[str]:
        try:
            return subprocess.run(args, stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                  stderr=subprocess.STDOUT, text=True, timeout=timeout,
                                  cwd=self._base, env=self._env(), **self._as_user())
        except subprocess.TimeoutExpired as e:
            raise PostgresError(f"{' '.join(args)} did not finish within {timeout:.0f} s") from e

    def _initdb(self) -> None:
        """A fresh cluster in a new temporary directory, tuned for tests (see the class docstring)."""
        # Under root the server user must reach the data: a directory of /tmp (mode 1777, so its
        # parents are traversable), opened to 0o755; TMPDIR could point somewhere private.
        self._user = _server_user()
        base = Path(tempfile.mkdtemp(prefix="hil-pg-", dir="/tmp" if self._user else None))
        self._base = base
        atexit.register(self.close)  # an interpreter that exits without close() stops the server too
        base.chmod(0o755)
        data = base / "data"
        data.mkdir(mode=0o700)
        log = base / "postgres.log"
        log.touch(mode=0o644)
        if self._user is not None:
            os.chown(data, self._user.pw_uid, self._user.pw_gid)
        result = self._run([self._bin("initdb"), "-D", str(data), "-U", SUPERUSER, "--auth=trust",
                            "-E", "UTF8", "--locale=C", "--no-sync"], timeout=self.timeout + 30)
        if result.returncode != 0:
            raise PostgresError(f"initdb failed ({result.returncode}):\n{result.stdout}")
        settings = {
            "listen_addresses": f"'{HOST}'",
            # The socket in the data directory: no /var/run/postgresql needed (nor shared with
            # another server), and it goes away with the directory.
            "unix_socket_directories": f"'{data}'",
            "max_connections": str(self.max_connections),
            # Dynamic shared memory as files in the data directory rather than in /dev/shm: a
            # killed server's segments go away with the directory, and a container's small
            # /dev/shm (64 MB under Docker) does not limit the tests.
            "dynamic_shared_memory_type": "mmap",
        }
        if self.fast:
            settings |= {"fsync": "off", "full_page_writes": "off"}
        with (data / "postgresql.conf").open("a") as conf:
            conf.write("\n# tests/pg_server.py\n")
            conf.writelines(f"{key} = {value}\n" for key, value in settings.items())

    def _launch(self, port: int) -> None:
        """Start the postmaster on `port` and wait (bounded) until it accepts connections."""
        with self.log_path.open("ab") as log:
            # In a session of its own, as pg_ctl does: a Ctrl-C at the terminal goes to pytest alone,
            # whose teardown then stops the server in order.
            self._proc = subprocess.Popen(
                [self._bin("postgres"), "-D", str(self.data_dir), "-p", str(port)],
                stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT, cwd=self._base,
                env=self._env(), start_new_session=True, **self._as_user())
        url = f"postgresql://{SUPERUSER}@{HOST}:{port}/postgres"
        deadline = time.monotonic() + self.timeout
        while True:
            if self._proc.poll() is not None:
                raise PostgresError(f"the server exited at start ({self._proc.returncode}):\n"
                                    f"{self._log_tail()}")
            try:
                with psycopg.connect(url, connect_timeout=2) as conn:
                    conn.execute("SELECT 1")
                return
            except psycopg.OperationalError:
                if time.monotonic() > deadline:
                    self.kill()
                    raise PostgresError(f"the server did not accept connections within "
                                        f"{self.timeout:.0f} s:\n{self._log_tail()}") from None
                time.sleep(0.05)

    def _log_tail(self, lines: int = 20) -> str:
        try:
            return "\n".join(self.log_path.read_text(errors="replace").splitlines()[-lines:])
        except (OSError, PostgresError):
            return "(no server log)"
