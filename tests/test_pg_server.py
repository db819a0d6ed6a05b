"""Issue 18: the PostgreSQL server the tests start themselves (tests/pg_server.py) and its fixtures.

The store's tests lean on it: a database of their own per test, a server that can be stopped,
restarted and killed mid-campaign with committed data intact, reachable from nowhere but 127.0.0.1.
"""

from __future__ import annotations

import errno
import os
import re
import socket
from pathlib import Path

import psycopg
import pytest

import tests.conftest as conftest
from tests.pg_server import BINARIES, PostgresServer, find_binaries
from tests.proc_tree import alive


def _count(url: str, table: str = "t") -> int:
    with psycopg.connect(url, connect_timeout=5) as conn:
        row = conn.execute(f"SELECT count(*) FROM {table}").fetchone()
        assert row is not None
        return int(row[0])


def _uid(pid: int) -> int:
    """The real uid of a running process."""
    for line in Path(f"/proc/{pid}/status").read_text().splitlines():
        if line.startswith("Uid:"):
            return int(line.split()[1])
    raise AssertionError(f"no Uid in /proc/{pid}/status")


def test_find_binaries_names_a_directory_holding_the_server_programs(postgres: PostgresServer) -> None:
    binaries = find_binaries()
    assert binaries is not None
    assert all(os.access(binaries / name, os.X_OK) for name in BINARIES)


def test_databases_of_their_own_on_the_session_server(postgres: PostgresServer, pg_url: str) -> None:
    assert re.fullmatch(rf"postgresql://hil@127\.0\.0\.1:{postgres.port}/hil_\d+", pg_url)
    other = postgres.create_database("other db")  # any name: an identifier, percent-encoded in URLs
    assert other == f"postgresql://hil@127.0.0.1:{postgres.port}/other%20db"
    for url, rows in ((pg_url, 3), (other, 5)):
        with psycopg.connect(url, connect_timeout=5) as conn:
            conn.execute("CREATE TABLE t (i int)")
            conn.cursor().executemany("INSERT INTO t VALUES (%s)", [(i,) for i in range(rows)])
    assert (_count(pg_url), _count(other)) == (3, 5)  # separate databases
    with postgres.connect() as conn:
        settings = {name: conn.execute(f"SHOW {name}").fetchone() for name in
                    ("fsync", "full_page_writes", "synchronous_commit", "max_connections",
                     "server_encoding")}
        user = conn.execute("SELECT current_user").fetchone()
    assert settings == {"fsync": ("off",), "full_page_writes": ("off",), "synchronous_commit": ("on",),
                        "max_connections": ("200",), "server_encoding": ("UTF8",)}
    assert user == ("hil",)


def test_the_server_is_reachable_on_127_0_0_1_only(postgres: PostgresServer) -> None:
    with postgres.connect() as conn:
        assert conn.execute("SHOW listen_addresses").fetchone() == ("127.0.0.1",)
        assert conn.execute("SHOW unix_socket_directories").fetchone() == (str(postgres.data_dir),)
    # 127.0.0.2 is loopback too on Linux: a server bound to every address would answer there.
    with socket.socket(socket.AF_INET, socket.SOCK_STREAM) as s:
        s.settimeout(5)
        assert s.connect_ex(("127.0.0.2", postgres.port)) == errno.ECONNREFUSED
    listening = []  # (address, port) of every TCP listener, IPv4 and IPv6, from the kernel's tables
    for table in ("/proc/net/tcp", "/proc/net/tcp6"):
        if os.path.exists(table):
            for line in Path(table).read_text().splitlines()[1:]:
                local, state = line.split()[1], line.split()[3]
                address, port = local.split(":")
                if state == "0A" and int(port, 16) == postgres.port:  # 0A: LISTEN
                    listening.append(address)
    assert listening == ["0100007F"]  # 127.0.0.1, little-endian; nothing on IPv6


def test_stop_and_restart_keep_the_data_and_the_url(own_postgres: PostgresServer) -> None:
    url = own_postgres.create_database("campaign")
    with psycopg.connect(url, autocommit=True) as conn:
        conn.execute("CREATE TABLE t (i int)")
        conn.execute("INSERT INTO t VALUES (1), (2)")
    port = own_postgres.port
    own_postgres.stop()
    assert not own_postgres.running
    with pytest.raises(psycopg.OperationalError):
        psycopg.connect(url, connect_timeout=2)
    own_postgres.start()
    assert own_postgres.port == port and own_postgres.url("campaign") == url
    assert _count(url) == 2


def test_a_killed_server_recovers_every_committed_transaction(own_postgres: PostgresServer) -> None:
    url = own_postgres.create_database("campaign")
    with psycopg.connect(url, autocommit=True) as conn:
        conn.execute("CREATE TABLE t (i int)")
        for i in range(50):  # each its own transaction, the last committed just before the kill
            conn.execute("INSERT INTO t VALUES (%s)", (i,))
    pending = psycopg.connect(url, connect_timeout=5)
    pending.execute("INSERT INTO t SELECT generate_series(1, 1000)")  # never committed
    postmaster = own_postgres.pid
    assert postmaster is not None
    if os.geteuid() == 0:  # initdb and postgres refuse root: the server runs as another user
        assert _uid(postmaster) != 0
    own_postgres.kill()
    assert not own_postgres.running and not alive(postmaster)
    with pytest.raises(psycopg.OperationalError):
        pending.execute("SELECT 1")
    pending.close()
    own_postgres.start()
    assert _count(url) == 50
    assert "automatic recovery in progress" in own_postgres.log_path.read_text()


def test_close_stops_the_server_and_removes_its_directory() -> None:
    conftest._postgres_binaries()  # skips (fails in CI) without PostgreSQL, as the fixtures do
    with PostgresServer() as server:
        base, postmaster = server.data_dir.parent, server.pid
        assert postmaster is not None and base.is_dir()
    assert not alive(postmaster)
    assert not base.exists()


def test_missing_postgresql_fails_in_ci_and_skips_elsewhere(monkeypatch: pytest.MonkeyPatch) -> None:
    monkeypatch.setattr(conftest, "find_binaries", lambda: None)
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception, match="CI is set and PostgreSQL server binaries"):
        conftest._postgres_binaries()
    monkeypatch.delenv("CI")
    with pytest.raises(pytest.skip.Exception, match="not found"):
        conftest._postgres_binaries()
