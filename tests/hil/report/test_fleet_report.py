"""`hil fleet-report`: one self-contained HTML file about the fleet (table, accuracy over time, the
distribution across the fleet, the stations side by side, the robots whose geometry moved, the marks),
and bad input (exit 2, one line, nothing written)."""

from __future__ import annotations

import re
import xml.etree.ElementTree as ET
from pathlib import Path

from hil.cli import main
from hil.report.fleet import fleet_data, render_fleet_html
from hil.store import Store
from hil.store.fleet import mark
from tests.hil.fleet_data import (
    DAY,
    HIT_PARAMETER,
    HIT_ROBOT,
    ROBOTS,
    STATIONS,
    STEADY,
    T0,
    Fleet,
    fingerprint,
)

PNG = re.compile(r'<img src="data:image/png;base64,[A-Za-z0-9+/=]+"')


def write(capsys, argv: list[str]) -> str:
    code = main(["fleet-report", *argv])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert captured.out == ""
    return captured.err


def run_bad(capsys, argv: list[str]) -> str:
    code = main(["fleet-report", *argv])
    captured = capsys.readouterr()
    err = captured.err.strip()
    assert code == 2, (code, err)
    assert len(err.splitlines()) == 1 and "Traceback" not in err, err
    return err


def self_contained(html: str) -> None:
    ET.fromstring(html.split("\n", 1)[1])  # well-formed XML after the doctype
    assert "<script" not in html and "<link" not in html
    assert not re.search(r"""src=["'](?!data:)""", html)  # nothing fetched from anywhere
    assert not re.search(r"""href=["'](?!#)""", html)  # links only within the page
    assert "url(" not in html


def test_the_report_shows_the_fleet_its_plots_and_the_moved_robot(fleet_store_location, built_fleet: Fleet,
                                                                 tmp_path, capsys):
    out = tmp_path / "fleet.html"
    err = write(capsys, ["--db", str(fleet_store_location), "--out", str(out)])
    assert err.strip() == f"wrote {out} (3 robots, 9 calibrations)"
    html = out.read_text()
    self_contained(html)
    assert len(PNG.findall(html)) == 3  # over time, distribution, stations
    for section in ("fleet", "time", "distribution", "stations", "moved", "marks"):
        assert f'<section id="{section}">' in html
    fleet_table = html.split('<section id="fleet">')[1].split("</section>")[0]
    assert all(serial in fleet_table for serial in ROBOTS)
    assert all(station in fleet_table for station in STATIONS)
    moved = html.split('<section id="moved">')[1].split("</section>")[0]
    ids = built_fleet.campaigns[HIT_ROBOT]
    assert HIT_ROBOT in moved and HIT_PARAMETER in moved and f"{ids[1]} → {ids[2]}" in moved
    assert STEADY not in moved
    assert "No calibration has been marked." in html


def test_marks_and_since(fleet_store_location, built_fleet: Fleet, tmp_path):
    with Store.open(fleet_store_location) as store:
        mark(store, built_fleet.campaigns[STEADY][0], bad=True, reason="SMR <nest> loose & re-glued",
             who="qa@plant")
        everything = fleet_data(store, now=T0 + 100 * DAY)
        recent = fleet_data(store, since=T0 + 50 * DAY, now=T0 + 100 * DAY)
        late = fleet_data(store, since=T0 + 99 * DAY, now=T0 + 100 * DAY)
    html = render_fleet_html(everything, generated="2024-05-01T00:00:00+00:00")
    self_contained(html)
    assert "SMR &lt;nest&gt; loose &amp; re-glued" in html and "qa@plant" in html
    assert "Generated 2024-05-01T00:00:00+00:00" in html
    assert len(recent.calibrations) == 3 and len(recent.robots) == 3
    assert [serial for serial, _ in recent.moved] == [HIT_ROBOT]  # the hit is after the day
    html = render_fleet_html(late)
    self_contained(html)
    assert len(PNG.findall(html)) == 1  # only the distribution: the fleet as it is now
    assert "No validated calibration in this period." in html and "No calibration in this period." in html
    assert "No robot's geometry moved beyond uncertainty." in html


def test_names_are_plain_text_in_figures_and_html(fleet_store_location, built_fleet: Fleet, tmp_path,
                                                  capsys):
    """A station named like mathtext (which would fail to parse) or like markup is drawn as typed."""
    odd = r"cell-$\frac$ <A&B>"
    with Store.open(fleet_store_location) as store:
        doc = store.model(built_fleet.campaigns[STEADY][-1])
        cid = store.create_campaign({"station": {"name": odd}, "robot": {"type": "ur5e"}},
                                    {"type": "ur5e", "serial": "$x_1$"}, now=T0 + 80 * DAY)
        store.save_model(cid, doc)
        store.save_validation(cid, {"rms": 2e-3, "max": 4e-3}, {"rms": 3e-5, "max": 6e-5}, True)
        store.set_status(cid, "accepted")
    out = tmp_path / "fleet.html"
    write(capsys, ["--db", str(fleet_store_location), "--out", str(out)])
    html = out.read_text()
    self_contained(html)
    assert r"cell-$\frac$ &lt;A&amp;B&gt;" in html and "$x_1$" in html


def test_an_empty_store_gives_a_report_without_figures(tmp_path, capsys):
    db = tmp_path / "empty.db"
    Store.open(db).close()
    out = tmp_path / "fleet.html"
    assert "(0 robots, 0 calibrations)" in write(capsys, ["--db", str(db), "--out", str(out)])
    html = out.read_text()
    self_contained(html)
    assert not PNG.findall(html) and "No robot with a known serial number in this store." in html


def test_bad_input_writes_nothing(fleet_store_location, tmp_path, capsys):
    db = str(fleet_store_location)
    before = fingerprint(fleet_store_location)
    out = tmp_path / "fleet.html"
    assert "--since" in run_bad(capsys, ["--db", db, "--out", str(out), "--since", "2024-13-01"])
    assert "--since" in run_bad(capsys, ["--db", db, "--out", str(out), "--since", "yesterday"])
    assert "--out" in run_bad(capsys, ["--db", db])
    if isinstance(fleet_store_location, Path):  # a file the report could overwrite
        err = run_bad(capsys, ["--db", db, "--out", db])
        assert "--out" in err and "is the store" in err
    assert "folder" in run_bad(capsys, ["--db", db, "--out", str(tmp_path / "no" / "fleet.html")])
    assert "--out" in run_bad(capsys, ["--db", db, "--out", str(tmp_path)])
    missing = tmp_path / "missing.db"
    assert "missing.db" in run_bad(capsys, ["--db", str(missing), "--out", str(out)])
    assert "--sigmas" in run_bad(capsys, ["--db", db, "--out", str(out), "--sigmas", "0"])
    assert not out.exists() and not missing.exists()
    assert fingerprint(fleet_store_location) == before


def test_an_interrupted_calibration_is_in_progress_not_a_result(fleet_store_location, built_fleet: Fleet,
                                                                tmp_path):
    """An interrupted (resumable) campaign is neither the robot's last calibration nor counted among
    the finished ones that were not accepted."""
    from hil.report.fleet import STATION_BARS, station_counts

    with Store.open(fleet_store_location) as store:
        before = fleet_data(store, now=T0 + 100 * DAY)
        cid = store.create_campaign({"station": {"name": STATIONS[0]}, "robot": {"type": "ur5e"}},
                                    {"type": "ur5e", "serial": STEADY}, now=T0 + 95 * DAY)
        store.set_status(cid, "interrupted")
        after = fleet_data(store, now=T0 + 100 * DAY)
    was, now = (station_counts(d.calibrations, STATIONS) for d in (before, after))
    accepted, other, going = STATION_BARS
    assert list(now[other]) == list(was[other]) and list(now[accepted]) == list(was[accepted])
    assert list(now[going]) == [1, 0] and not was[going].any()
    html = render_fleet_html(after)
    self_contained(html)
    row = next(r for r in html.split('<section id="fleet">')[1].split("<tr>") if STEADY in r)
    assert '<span class="ok">accepted</span>' in row and built_fleet.campaigns[STEADY][-1] in row
    assert f"in progress: interrupted (resumable)<br />{_local_day(T0 + 95 * DAY)} {cid}" in row
    assert "<b>9</b>" in html and "accepted, 1 in progress" in html  # 9 finished, 1 in progress


def _local_day(t: float) -> str:
    import datetime as dt

    return dt.datetime.fromtimestamp(t).strftime("%Y-%m-%d")
