"""Who sees what of a project, through the service API as a route would call it.

The meeting of docs/projects.md: the OEM team (alice, bob) sees every candidate; supplier X's
engineer (carol) only X's tire and the targets; supplier Y's (dave) only Y's; eve belongs to
another project's group and mallory to none. Every read a route makes is tried for every
user, and what a user may not see must not appear anywhere in what it gets: not in the
result, not in an error message.
"""

from __future__ import annotations

import dataclasses
import hashlib
import math

import pytest

from app.projects import (
    ANOTHER_CANDIDATE,
    AccessConfigError,
    AccessDenied,
    Conflict,
    NotFound,
    ProjectError,
    Projects,
    parse_access_file,
    parse_groups,
    upload_digest,
)
from app.projects.config import load_access_config

GROUPS = "oem:alice,bob;supplier_x:carol;supplier_y:dave;other:eve"

X_FILE = b"supplier X tire model bytes" * 100
Y_FILE = b"supplier Y tire model bytes" * 100
INCUMBENT_FILE = b"incumbent tire model" * 100
TARGET_FILE = b"harmonic,dof,freq_Hz,level_dB\n1,bushing:z,10,-40\n"


@pytest.fixture()
def meeting(tmp_path):
    p = Projects(tmp_path, parse_groups(GROUPS))
    info = p.create_project(
        "alice",
        "rear axle, summer tire sourcing 2027",
        {"oem": None, "supplier_x": ["Supplier X"], "supplier_y": ["supplier  y"]},
    )
    pid = info.id
    cx = p.add_candidate(
        "carol", pid, "x_v2.h5", X_FILE, {"name": "Xylo Grip", "supplier": "Supplier X"}
    )
    cy = p.add_candidate(
        "alice", pid, "y_v1.h5", Y_FILE, {"name": "Yonder Comfort", "supplier": "Supplier Y"}
    )
    ci = p.add_candidate(
        "bob", pid, "inc.h5", INCUMBENT_FILE, {"name": "Incumbent Ivo", "supplier": "OEM"}
    )
    target = p.add_target("alice", pid, "targets.csv", TARGET_FILE, "bushing targets")
    all_view = p.save_view(
        "alice", pid, "Overlay of all three", "?tab=verdict", [cx.id, cy.id, ci.id]
    )
    x_view = p.save_view("carol", pid, "Xylo alone", f"?tire={cx.digest}")
    oem_note = p.add_note("alice", pid, "Yonder is 2 dB over at 180 Hz")
    shared_note = p.add_note("alice", pid, "Meeting at 10:00", shared=True)
    x_note = p.add_note("carol", pid, "Xylo v3 due in March")
    other = p.create_project("eve", "front axle winter", {"other": None})
    return dict(
        p=p,
        pid=pid,
        cx=cx,
        cy=cy,
        ci=ci,
        target=target,
        all_view=all_view,
        x_view=x_view,
        notes=(oem_note, shared_note, x_note),
        other=other,
    )


SECRETS_OF_Y = ("Yonder", "y_v1.h5")
SECRETS_OF_P1 = ("rear axle", "Xylo", "Yonder", "Incumbent", "Overlay", "bushing targets")


def _everything(m, user):
    """Every read a route makes of the meeting's project, as ``user``: name -> result or
    the error it raised."""
    p, pid = m["p"], m["pid"]
    calls = {
        "list": lambda: p.list_projects(user),
        "open": lambda: p.open_project(user, pid),
        "x file": lambda: p.candidate_file(user, pid, m["cx"].id),
        "y file": lambda: p.candidate_file(user, pid, m["cy"].id),
        "incumbent file": lambda: p.candidate_file(user, pid, m["ci"].id),
        "target file": lambda: p.target_file(user, pid, m["target"].id),
        "all view": lambda: p.resolve_view(user, m["all_view"]),
        "x view": lambda: p.resolve_view(user, m["x_view"]),
        "notes": lambda: p.notes(user, pid),
        "audit": lambda: p.audit(user, pid),
        "export": lambda: p.record_export(user, pid, "report.pdf"),
    }
    out = {}
    for name, call in calls.items():
        try:
            out[name] = call()
        except ProjectError as exc:
            out[name] = exc
    return out


# user -> which of the reads succeed (True) or are refused (the error's class)
TABLE = {
    "alice": {
        "x file": True,
        "y file": True,
        "incumbent file": True,
        "target file": True,
        "all view": True,
        "x view": True,
    },
    "carol": {
        "x file": True,
        "y file": NotFound,
        "incumbent file": NotFound,
        "target file": True,
        "all view": AccessDenied,
        "x view": True,
    },
    "dave": {
        "x file": NotFound,
        "y file": True,
        "incumbent file": NotFound,
        "target file": True,
        "all view": AccessDenied,
        "x view": AccessDenied,
    },
    "eve": {
        k: AccessDenied
        for k in ("x file", "y file", "incumbent file", "target file", "all view", "x view")
    },
    "mallory": {
        k: AccessDenied
        for k in ("x file", "y file", "incumbent file", "target file", "all view", "x view")
    },
}


@pytest.mark.parametrize("user", sorted(TABLE))
def test_the_access_table_route_by_route(meeting, user):
    got = _everything(meeting, user)
    for name, expected in TABLE[user].items():
        if expected is True:
            assert not isinstance(got[name], Exception), (user, name, got[name])
        else:
            assert type(got[name]) is expected, (user, name, got[name])
    files = {"x file": X_FILE, "y file": Y_FILE, "incumbent file": INCUMBENT_FILE}
    for name, data in files.items():
        if TABLE[user][name] is True:
            assert got[name][1] == data  # the file as uploaded, bit for bit


def _text_of(obj) -> str:
    """Every string and bytes inside ``obj`` (records, tuples, errors), joined."""
    if isinstance(obj, Exception):
        return str(obj)
    if isinstance(obj, bytes):
        return obj.decode("latin-1")
    if isinstance(obj, str):
        return obj
    if dataclasses.is_dataclass(obj):
        return " ".join(_text_of(getattr(obj, f.name)) for f in dataclasses.fields(obj))
    if isinstance(obj, dict):
        return " ".join(_text_of(k) + " " + _text_of(v) for k, v in obj.items())
    if isinstance(obj, tuple | list | frozenset | set):
        return " ".join(_text_of(x) for x in obj)
    return repr(obj)


@pytest.mark.parametrize("user", ["eve", "mallory"])
def test_another_group_gets_nothing_of_the_project(meeting, user):
    got = _everything(meeting, user)
    assert got["list"] == () or all(i.id != meeting["pid"] for i in got["list"])
    for name, result in got.items():
        if name == "list":
            continue
        assert isinstance(result, AccessDenied), (name, result)
    text = _text_of(got)
    for secret in SECRETS_OF_P1:
        assert secret not in text, secret
    assert "supplier X tire" not in text  # no file content


def test_a_supplier_sees_its_candidate_and_the_targets_not_the_others(meeting):
    got = _everything(meeting, "carol")
    page = got["open"]
    assert [c.name for c in page.candidates] == ["Xylo Grip"]
    assert [t.name for t in page.targets] == ["bushing targets"]
    assert [v.name for v in page.views] == ["Xylo alone"]
    assert not page.full_access
    # the access list shows its own group only: not which other suppliers take part
    assert [a.group for a in page.info.access] == ["supplier_x"]
    assert {n.text for n in page.notes} == {"Meeting at 10:00", "Xylo v3 due in March"}
    text = _text_of(got)
    for secret in (*SECRETS_OF_Y, "Incumbent", "inc.h5", "supplier_y", "2 dB over"):
        assert secret not in text, secret
    # the audit log tells carol of her own additions and of alice's shared actions only
    audit_what = [e.what for e in got["audit"]]
    assert "candidate 'Xylo Grip'" in audit_what
    assert not any("Yonder" in w or "Incumbent" in w for w in audit_what)


def test_the_oem_team_sees_everything(meeting):
    page = meeting["p"].open_project("bob", meeting["pid"])
    assert [c.name for c in page.candidates] == ["Xylo Grip", "Yonder Comfort", "Incumbent Ivo"]
    assert {v.name for v in page.views} == {"Overlay of all three", "Xylo alone"}
    assert len(page.notes) == 3
    assert page.full_access


def test_supplier_names_are_compared_without_case_and_spacing(meeting):
    # supplier_y was granted "supplier  y"; the candidate says "Supplier Y"
    page = meeting["p"].open_project("dave", meeting["pid"])
    assert [c.name for c in page.candidates] == ["Yonder Comfort"]


def test_a_view_link_of_a_project_you_may_not_open_says_so(meeting):
    with pytest.raises(AccessDenied, match="a project you may not open") as err:
        meeting["p"].resolve_view("eve", meeting["all_view"])
    assert "Overlay" not in str(err.value) and "rear axle" not in str(err.value)
    with pytest.raises(NotFound):
        meeting["p"].resolve_view("alice", meeting["pid"] + "-AAAAAAAAAAAA")
    with pytest.raises(NotFound):
        meeting["p"].resolve_view("alice", "../../etc/passwd")


def test_writes_are_checked_too(meeting):
    p, pid = meeting["p"], meeting["pid"]
    with pytest.raises(AccessDenied, match="Supplier X only|supplier x only"):
        p.add_candidate("carol", pid, "fake.h5", b"fake", {"name": "Y2", "supplier": "Supplier Y"})
    with pytest.raises(NotFound):
        p.remove_candidate("carol", pid, meeting["cy"].id)
    with pytest.raises(AccessDenied):
        p.add_target("carol", pid, "t.csv", b"t", "my own targets")
    with pytest.raises(AccessDenied):
        p.remove_target("dave", pid, meeting["target"].id)
    with pytest.raises(AccessDenied):
        p.set_access("carol", pid, {"supplier_x": None})
    with pytest.raises(NotFound):  # a view naming a candidate carol may not see
        p.save_view("carol", pid, "peek", "?x=1", [meeting["cy"].id])
    with pytest.raises(NotFound):  # the same through the query text
        p.save_view("carol", pid, "peek", f"?tire={meeting['cy'].digest}")
    with pytest.raises(AccessDenied):
        p.add_note("carol", pid, "for everyone", shared=True)
    for user in ("eve", "mallory"):
        with pytest.raises(AccessDenied):
            p.add_candidate(user, pid, "z.h5", b"z", {"name": "Z", "supplier": "Z"})
        with pytest.raises(AccessDenied):
            p.save_view(user, pid, "v", "?a=1")
        with pytest.raises(AccessDenied):
            p.add_note(user, pid, "hello")
    # nothing of the refused writes is in the project
    page = p.open_project("alice", pid)
    assert len(page.candidates) == 3 and len(page.targets) == 1 and len(page.views) == 2
    assert len(page.notes) == 3


def test_changing_access_takes_effect_and_keeps_an_administrator(meeting):
    p, pid = meeting["p"], meeting["pid"]
    with pytest.raises(Conflict, match="shut you out"):
        p.set_access("alice", pid, {"supplier_x": ["Supplier X"]})
    p.set_access("alice", pid, {"oem": None, "supplier_x": ["Supplier X"]})
    with pytest.raises(AccessDenied):
        p.open_project("dave", pid)
    assert [i.id for i in p.list_projects("dave")] == []


def test_a_name_used_by_a_hidden_candidate_tells_the_supplier_nothing(meeting):
    p, pid = meeting["p"], meeting["pid"]
    # dave (supplier Y) names his new delivery like X's candidate he cannot see: it lands
    c = p.add_candidate(
        "dave", pid, "y_v2.h5", b"Y v2 bytes", {"name": "Xylo Grip", "supplier": "Supplier Y"}
    )
    assert [x.name for x in p.open_project("dave", pid).candidates] == ["Yonder Comfort", c.name]
    assert len([x for x in p.open_project("alice", pid).candidates if x.name == "Xylo Grip"]) == 2
    # and a file identical to a hidden candidate's is refused without naming it
    with pytest.raises(Conflict, match="holds this file already") as err:
        p.add_candidate("dave", pid, "copy.h5", X_FILE, {"name": "copy", "supplier": "Supplier Y"})
    assert "Xylo" not in str(err.value)


def test_a_removed_candidates_view_still_opens_and_names_it(meeting):
    p, pid = meeting["p"], meeting["pid"]
    p.remove_candidate("carol", pid, meeting["cx"].id)
    seen = p.resolve_view("alice", meeting["all_view"])
    assert seen.missing == ("Xylo Grip",)
    assert seen.query == "tab=verdict"
    assert p.resolve_view("carol", meeting["x_view"]).missing == ("Xylo Grip",)
    page = p.open_project("carol", pid)
    assert page.candidates == () and [c.name for c in page.removed] == ["Xylo Grip"]
    with pytest.raises(NotFound, match="removed"):
        p.candidate_file("alice", pid, meeting["cx"].id)
    # its file is gone from the data directory; the others stay
    files = p.store.project(pid).files
    names = {f.name for f in files.iterdir()}
    assert hashlib.sha256(X_FILE).hexdigest() not in names
    assert hashlib.sha256(Y_FILE).hexdigest() in names
    # a removed target: gone from the page and the data directory, its file refused
    t = p.remove_target("alice", pid, meeting["target"].id)
    assert t.removed and p.open_project("carol", pid).targets == ()
    with pytest.raises(NotFound, match="removed"):
        p.target_file("carol", pid, t.id)
    assert hashlib.sha256(TARGET_FILE).hexdigest() not in {f.name for f in files.iterdir()}
    # the same file may be added again as a new candidate
    again = p.add_candidate(
        "carol", pid, "x_v2.h5", X_FILE, {"name": "Xylo Grip", "supplier": "Supplier X"}
    )
    assert again.id != meeting["cx"].id


def test_the_audit_log_records_who_did_what(meeting):
    p, pid = meeting["p"], meeting["pid"]
    p.open_project("bob", pid)
    p.candidate_file("carol", pid, meeting["cx"].id)
    p.resolve_view("alice", meeting["all_view"])
    p.record_export("alice", pid, "report rear_axle.pdf", [meeting["cy"].id])
    p.remove_candidate("alice", pid, meeting["cy"].id)
    log = [(e.user, e.action, e.what) for e in p.audit("alice", pid)]
    assert log[0] == ("alice", "created", "project 'rear axle, summer tire sourcing 2027'")
    for line in [
        ("carol", "added", "candidate 'Xylo Grip'"),
        ("alice", "added", "candidate 'Yonder Comfort'"),
        ("alice", "added", "target 'bushing targets'"),
        ("alice", "saved view", "view 'Overlay of all three'"),
        ("bob", "opened", "project 'rear axle, summer tire sourcing 2027'"),
        ("carol", "exported", "file of candidate 'Xylo Grip'"),
        ("alice", "viewed", "view 'Overlay of all three'"),
        ("alice", "exported", "report rear_axle.pdf"),
        ("alice", "removed", "candidate 'Yonder Comfort'"),
    ]:
        assert line in log, line
    # append-only: the database itself refuses to change or delete a line
    import sqlite3

    conn = sqlite3.connect(p.store.project(pid).db)
    for sql in ("UPDATE audit SET user = 'x'", "DELETE FROM audit"):
        with pytest.raises(sqlite3.DatabaseError, match="append-only"):
            conn.execute(sql)
    conn.close()
    assert len(p.audit("alice", pid)) == len(log) + 0  # audit() itself is not logged


@dataclasses.dataclass(frozen=True)
class Standing:
    """The shape of ``fbs_core.verdict.Standing``: what the redaction works on."""

    rank: int
    candidate: str
    digest: str
    status: str
    worst_db: float
    harmonic: int
    dof: str


def test_the_ranking_shown_to_a_supplier_names_only_its_own_candidate(meeting):
    p, pid = meeting["p"], meeting["pid"]
    cx, cy, ci = meeting["cx"], meeting["cy"], meeting["ci"]
    ranking = (
        Standing(1, cy.name, cy.digest, "pass", -3.0, 2, "bushing:z"),
        Standing(2, "reference tire", "reference", "pass", -1.0, 2, "bushing:z"),
        Standing(3, cx.name, cx.digest, "fail", 2.5, 3, "bushing:x"),
        Standing(4, ci.name, ci.digest, "fail", 4.0, 1, "bushing:y"),
    )
    shown = p.ranking("carol", pid, ranking)
    assert [s.rank for s in shown] == [1, 2, 3, 4]
    assert shown[2] == ranking[2] and shown[1] == ranking[1]
    for s in (shown[0], shown[3]):
        assert s.candidate == ANOTHER_CANDIDATE
        assert s.digest == "" and s.status == "" and s.dof == "" and s.harmonic == 0
        assert math.isnan(s.worst_db)
    assert "Yonder" not in _text_of(shown) and "Incumbent" not in _text_of(shown)
    assert p.ranking("alice", pid, ranking) == ranking
    with pytest.raises(AccessDenied):
        p.ranking("eve", pid, ranking)
    # mappings (a table's rows) are redacted the same way
    rows = [dataclasses.asdict(s) for s in ranking]
    shown_rows = p.ranking("dave", pid, rows)
    assert [r["candidate"] for r in shown_rows] == [
        cy.name,
        "reference tire",
        ANOTHER_CANDIDATE,
        ANOTHER_CANDIDATE,
    ]


def test_the_digest_and_size_limit_are_the_dashboards():
    from app.datasource import _digest
    from app.projects.service import DEFAULT_MAX_BYTES
    from fbs_core.io.checks import DEFAULT_MAX_BYTES as core_limit

    assert DEFAULT_MAX_BYTES == core_limit

    for data in (b"", b"abc", X_FILE):
        assert upload_digest(data) == _digest(data)


@pytest.mark.parametrize(
    ("text", "message"),
    [
        ("oem alice", "entry 1.*expected group:user"),
        ("oem:alice;oem:bob", "group 'oem' is given twice"),
        ("oem:", "group 'oem' has no users"),
        ("o em:alice", "group name 'o em'"),
        ("oem:alice;supplier x:carol", "entry 2"),
    ],
)
def test_a_malformed_groups_setting_names_the_entry(text, message):
    with pytest.raises(AccessConfigError, match=message):
        parse_groups(text)


def test_groups_from_the_setting_and_from_a_toml_file(tmp_path):
    cfg = parse_groups("oem: alice, bob\nsupplier_x:carol")
    assert cfg.user("bob").groups == frozenset({"oem"})
    assert cfg.user("nobody").groups == frozenset()
    assert cfg.unknown_users(["alice", "carol"]) == ("bob",)
    f = tmp_path / "access.toml"
    f.write_text('[groups]\noem = ["alice", "bob"]\nsupplier_x = ["carol"]\n')
    assert parse_access_file(f).groups == cfg.groups
    env = {"FBS_ACCESS_FILE": str(f)}
    assert load_access_config(env).groups == cfg.groups
    with pytest.raises(AccessConfigError, match="not both"):
        load_access_config({**env, "FBS_GROUPS": "oem:alice"})
    for content, message in [
        ("[groups]\noem = 'alice'\n", "groups.oem: must be a non-empty list"),
        ("oem = ['alice']\n", r"needs a \[groups\] table"),
        ("[groups\n", "not valid TOML"),
        ("[groups]\noem = ['al:ice']\n", "user name 'al:ice'"),
    ]:
        f.write_text(content)
        with pytest.raises(AccessConfigError, match=message):
            parse_access_file(f)
    with pytest.raises(AccessConfigError, match="cannot be read"):
        parse_access_file(tmp_path / "missing.toml")


def test_bad_input_names_the_problem_and_changes_nothing(meeting):
    p, pid = meeting["p"], meeting["pid"]
    before = p.open_project("alice", pid)
    cases = [
        (lambda: p.add_candidate("alice", pid, "e.h5", b"", {"name": "E"}), "is empty"),
        (lambda: p.add_candidate("alice", pid, "e.h5", b"e", {"name": " "}), "must not be empty"),
        (
            lambda: p.add_candidate("alice", pid, "e.h5", b"e", {"name": "E", "colour": "red"}),
            "unknown field 'colour'",
        ),
        (
            lambda: p.add_candidate(
                "alice", pid, "x.h5", X_FILE, {"name": "X again", "supplier": "Supplier X"}
            ),
            "same file is candidate 'Xylo Grip'",
        ),
        (
            lambda: p.add_candidate(
                "alice", pid, "n.h5", b"new", {"name": "xylo grip", "supplier": "Supplier X"}
            ),
            "Supplier X has a candidate of that name",
        ),
        (lambda: p.save_view("alice", pid, "v", "a=1\nb=2"), "control characters"),
        (lambda: p.save_view("alice", pid, "v", "a" * 9000), "at most 8000"),
        (lambda: p.create_project("alice", "t", {"nope": None}), "group 'nope' is not among"),
        (lambda: p.create_project("carol", "t", {"supplier_x": ["X"]}), "as seeing all"),
        (lambda: p.open_project("alice", "0123456789abcdef"), "no project"),
        (lambda: p.add_note("alice", pid, "n" * 2001), "at most 2000"),
    ]
    for call, message in cases:
        with pytest.raises(ProjectError, match=message):
            call()
    after = p.open_project("alice", pid)
    assert (after.candidates, after.views, after.notes) == (
        before.candidates,
        before.views,
        before.notes,
    )


def test_the_server_start_turns_projects_on_only_with_groups(tmp_path, caplog):
    from app.projects import AccessConfigError, projects_at_start

    assert projects_at_start({"FBS_DATA_DIR": str(tmp_path)}) is None
    assert not (tmp_path / "projects").exists()  # nothing written when off
    env = {"FBS_DATA_DIR": str(tmp_path), "FBS_GROUPS": "oem:alice,bob"}
    p = projects_at_start(env, logins=["alice"])
    assert p is not None and p.list_projects("alice") == ()
    assert "group members without a login: bob" in caplog.text
    with pytest.raises(AccessConfigError, match="FBS_GROUPS entry 1"):
        projects_at_start({**env, "FBS_GROUPS": "oem alice"})
    blocked = tmp_path / "file"
    blocked.write_text("not a directory")
    with pytest.raises(ProjectError, match="set FBS_DATA_DIR to a writable directory"):
        projects_at_start({**env, "FBS_DATA_DIR": str(blocked)})
