"""A damaged row of the store is named (campaign, table, id, column) as bad input; listings read the
rest (issue 31, class 5)."""

from __future__ import annotations

import sqlite3

import pytest

from hil.errors import InputError
from hil.station.config import default_config
from hil.store import RobotIdentity, Store
from hil.store.rows import DamagedRowError, row_json


def test_row_json_names_the_row() -> None:
    assert row_json('{"a": 1}', table="models", row=3, column="doc") == {"a": 1}
    assert row_json(None, table="models", row=3, column="doc") is None
    with pytest.raises(DamagedRowError, match=r"^damaged store row: campaign C-1, table models, id 3: doc "
                                              r"is not valid JSON \(Expecting value\)$"):
        row_json("nope", table="models", row=3, column="doc", campaign="C-1")
    assert issubclass(DamagedRowError, InputError)  # exit 2 on the command line


@pytest.fixture
def store_with_a_campaign(tmp_path):
    path = tmp_path / "s.db"
    with Store.open(path) as s:
        robot = RobotIdentity("ur5e", "20235500001", "UR5e", "5.15")
        cid = s.create_campaign(default_config().as_dict(), robot, {"method": "tabu"}, now=1.7e9)
        s.save_plan(cid, [(0, "calibration", [0.0, -1.0, 1.0, 0.0, 1.0, 0.0])])
    return path, cid


@pytest.mark.parametrize(("sql", "table", "column"), [
    ("UPDATE campaigns SET config = '{broken'", "campaigns", "config"),
    ("UPDATE poses SET target = '['", "poses", "target"),
])
def test_show_names_the_damaged_row_and_history_lists_the_rest(store_with_a_campaign, sql, table,
                                                               column) -> None:
    path, cid = store_with_a_campaign
    conn = sqlite3.connect(path)
    conn.execute(sql)
    conn.commit()
    conn.close()
    with Store.open(path, readonly=True, create=False) as s:
        assert [c.id for c in s.campaigns()] == [cid]  # the listing reads it
        with pytest.raises(DamagedRowError, match=f"campaign {cid}, table {table}, id .*: {column} is not "
                                                  "valid JSON"):
            s.campaign(cid)
