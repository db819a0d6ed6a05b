"""Issue 19, "two campaigns, one arm": the store's campaign and robot leases and the host-local address
lock (hil.store.leases) — one process per campaign, one campaign per arm, a dead owner taken over."""

from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import pytest

from hil.errors import InputError
from hil.station.config import default_config
from hil.store import LeaseRefused, RobotIdentity, Store, address_lock
from hil.store.owner import this_process
from tests.hil.store.raw import raw, raw_write

ROOT = Path(__file__).resolve().parents[3]
ROBOT = RobotIdentity(type="ur5e", serial="20235500123", model="UR5e", software="5.15.0")


def cfg(name: str = "cell-1") -> dict:
    data = default_config().as_dict()
    data["station"]["name"] = name
    return data


@pytest.fixture(params=["sqlite", "postgresql"])
def db(request, tmp_path) -> Path | str:
    """Both engines: the leases are plain SQL a PostgreSQL store shared by many stations runs too."""
    return tmp_path / "hil.db" if request.param == "sqlite" else request.getfixturevalue("pg_url")


@pytest.fixture
def store(db):
    with Store.open(db) as s:
        yield s


def leases(db: Path) -> dict[str, tuple[str, dict]]:
    with Store.open(db) as s:
        return {name: (campaign, json.loads(owner)) for name, campaign, owner in
                raw(s).execute("SELECT name, campaign, owner FROM leases")}


def test_a_live_owner_keeps_its_campaign_and_a_second_claim_is_refused_in_one_line(store, db):
    cid = store.create_campaign(cfg(), ROBOT)
    with store.claim(cid, ROBOT.serial) as lease:
        assert lease.campaign == cid
        held = leases(db)
        assert set(held) == {f"campaign:{cid}", f"robot:{ROBOT.serial}"}
        assert held[f"campaign:{cid}"][1]["pid"] == os.getpid()
        # another connection, the same (live) process: refused
        with Store.open(db) as other, pytest.raises(LeaseRefused) as refused:
            other.claim(cid, ROBOT.serial)
        text = str(refused.value)
        assert "\n" not in text
        assert f"campaign {cid} is being run by pid {os.getpid()} on host {socket.gethostname()} since " \
            in text
        assert isinstance(refused.value, InputError)  # the CLI's exit 2
    assert leases(db) == {}  # released when the run ends
    store.claim(cid, ROBOT.serial).release()  # and claimable again


def test_one_arm_one_campaign_even_for_two_configs_and_a_refusal_leaves_nothing_behind(store, db):
    first = store.claim_new(cfg("cell-1"), ROBOT)
    other = store.create_campaign(cfg("cell-2"), ROBOT)
    with pytest.raises(LeaseRefused, match=rf"robot {ROBOT.serial} is being driven by campaign "
                                           rf"{first.campaign} \(pid {os.getpid()} on host "):
        store.claim_new(cfg("cell-2"), ROBOT)
    with pytest.raises(LeaseRefused, match=f"campaign {other} cannot use it"):
        store.claim(other, ROBOT.serial)
    # atomic: neither the refused new campaign nor the other campaign's lease was left in the store
    assert {c.id for c in store.campaigns()} == {first.campaign, other}
    assert set(leases(db)) == {f"campaign:{first.campaign}", f"robot:{ROBOT.serial}"}
    # another arm is free; an arm of unknown serial takes no robot lease (the address lock covers it)
    store.claim(other, "another-arm").release()
    store.claim_new(cfg("cell-3"), RobotIdentity(type="ur5e")).release()
    first.release()
    store.claim(other, ROBOT.serial).release()


def test_a_finished_campaign_cannot_be_claimed(store):
    cid = store.create_campaign(cfg(), ROBOT)
    store.set_status(cid, "accepted")
    with pytest.raises(InputError, match=f"campaign {cid} is already accepted"):
        store.claim(cid, ROBOT.serial)


CHILD = textwrap.dedent("""
    import sys, time
    from hil.store import Store
    store = Store.open(sys.argv[1])
    lease = store.claim(sys.argv[2], "20235500123", heartbeat=False)
    print("claimed", flush=True)
    time.sleep(60)
""")


def test_the_lease_of_a_process_killed_with_sigkill_is_taken_over(store, db):
    """A real second process holds the lease; while it lives the claim is refused, after kill -9 it
    is taken over (the campaign is resumable)."""
    cid = store.create_campaign(cfg(), ROBOT)
    child = subprocess.Popen([sys.executable, "-c", CHILD, str(db), cid], cwd=ROOT, stdout=subprocess.PIPE,
                             text=True)
    try:
        assert child.stdout.readline().strip() == "claimed"
        with pytest.raises(LeaseRefused, match=f"pid {child.pid} "):
            store.claim(cid, ROBOT.serial)
        with pytest.raises(LeaseRefused, match=f"pid {child.pid} "):
            store.check_claim(None, ROBOT.serial)  # what the TUI asks before starting a run
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait()
        child.stdout.close()
    with store.claim(cid, ROBOT.serial):
        assert {owner["pid"] for _, owner in leases(db).values()} == {os.getpid()}


def _owner_elsewhere(db: Path, heartbeat: float) -> None:
    """Make every lease row look held by a process on another host (which is_gone cannot check)."""
    elsewhere = json.dumps({**this_process(), "host": "another-host"})
    with Store.open(db) as s, raw_write(s) as conn:
        conn.execute("UPDATE leases SET owner = ?, heartbeat = ?", (elsewhere, heartbeat))


def test_a_lease_held_from_another_host_expires_only_without_heartbeat(store, db):
    cid = store.create_campaign(cfg(), ROBOT)
    store.claim(cid, ROBOT.serial, heartbeat=False)  # then "moved" to another host
    _owner_elsewhere(db, time.time())
    with pytest.raises(LeaseRefused, match="pid .* on host another-host"):
        store.claim(cid, ROBOT.serial, ttl=30.0)
    _owner_elsewhere(db, time.time() - 31.0)  # no heartbeat for longer than the ttl: gone
    store.claim(cid, ROBOT.serial, ttl=30.0).release()


def test_the_heartbeat_keeps_a_lease_alive_and_notices_a_takeover(store, db):
    cid = store.create_campaign(cfg(), ROBOT)
    lease = store.claim(cid, ROBOT.serial, ttl=0.4)
    reasons: list[str] = []
    lease.on_lost = reasons.append
    try:
        _owner_elsewhere(db, time.time() - 10.0)  # stale now, but the heartbeat renews it
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline:
            with Store.open(db) as s:
                beats = [b for (b,) in raw(s).execute("SELECT heartbeat FROM leases")]
            if min(beats) > time.time() - 5.0:
                break
            time.sleep(0.05)
        with pytest.raises(LeaseRefused):
            store.claim(cid, ROBOT.serial, ttl=5.0)
        with Store.open(db) as s, raw_write(s) as conn:  # someone took it over
            conn.execute("UPDATE leases SET token = 'theirs'")
        assert lease.lost.wait(5.0)
        assert reasons and f"campaign {cid}" in reasons[0] and "taken over" in reasons[0]
    finally:
        lease.release()
    assert set(leases(db)) == {f"campaign:{cid}", f"robot:{ROBOT.serial}"}  # theirs stays


def test_the_address_lock_is_one_per_arm_and_dies_with_its_process(tmp_path):
    with address_lock("10.0.0.7", what="hil calibrate") as path:
        # a second holder, even in the same process
        with pytest.raises(LeaseRefused) as refused, address_lock("10.0.0.7"):
            pass
        text = str(refused.value)
        assert text.startswith("the robot at 10.0.0.7 is in use by hil calibrate "
                               f"(pid {os.getpid()} on host {socket.gethostname()} since ")
        assert "\n" not in text and str(path) in text
        with address_lock("10.0.0.8"):  # another arm
            pass
    with address_lock("10.0.0.7"):  # released
        pass
    child = subprocess.Popen(
        [sys.executable, "-c", "import sys, time; from hil.store import address_lock\n"
                               "with address_lock('10.0.0.7', what='child'):\n"
                               "    print('locked', flush=True); time.sleep(60)"],
        cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        assert child.stdout.readline().strip() == "locked"
        busy = pytest.raises(LeaseRefused, match=f"in use by child \\(pid {child.pid} ")
        with busy, address_lock("10.0.0.7"):
            pass
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait()
        child.stdout.close()
    with address_lock("10.0.0.7"):  # the kernel released it with the process
        pass


def test_two_threads_racing_for_one_campaign_get_one_lease(store, db):
    cid = store.create_campaign(cfg(), ROBOT)
    won: list[object] = []
    refused: list[BaseException] = []
    start = threading.Barrier(4)

    def race() -> None:
        with Store.open(db) as s:
            start.wait()
            try:
                won.append(s.claim(cid, ROBOT.serial, heartbeat=False))
            except LeaseRefused as exc:
                refused.append(exc)

    threads = [threading.Thread(target=race) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(won) == 1 and len(refused) == 3
