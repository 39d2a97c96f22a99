"""The deployment's public base URL (``FBS_PUBLIC_URL``, issue 29): every link a page hands
out (the HTML and PDF reports, CSV headers, title blocks) starts with it, so a recipient
outside the server's network opens the page; a wrong value is refused, naming it."""

from __future__ import annotations

import importlib.util
import io
import re
import sys
from pathlib import Path

import pytest

from app.public_url import PublicURLError, check_public_url, public_link

ROOT = Path(__file__).resolve().parents[1]
BASE = "https://nvh.example.com/tire-fbs"
#: Addresses inside an SVG or PDF that are no links (XML namespaces).
NAMESPACES = ("http://www.w3.org/",)


@pytest.mark.parametrize(
    ("value", "match"),
    [
        ("nvh.example.com", "must start with http:// or https://"),
        ("ftp://nvh.example.com", "must start with http:// or https://"),
        ("javascript:alert(1)", "must start with http:// or https://"),
        ("https://", "names no host"),
        ("https://nvh.example.com/?a=1", "must not hold a query"),
        ("https://nvh.example.com/#x", "must not hold a query"),
        ("https://u:p@nvh.example.com", "user name or password"),
        ('https://nvh.example.com/"><b>', "must not contain"),
        ("https://nvh example.com", "must not contain"),
        ("https://nvh.example.com:99999", "port is not a number"),
    ],
)
def test_an_invalid_public_url_is_refused_naming_the_variable(value, match):
    with pytest.raises(PublicURLError, match=match) as e:
        check_public_url(value)
    assert str(e.value).startswith(f"FBS_PUBLIC_URL={value!r}")
    assert isinstance(e.value, ValueError)


def test_the_link_keeps_the_pages_path_and_query_behind_the_base():
    env = {"FBS_PUBLIC_URL": BASE + "/"}
    assert public_link("http://localhost:5006/main?h=4&N=60", env) == BASE + "/main?h=4&N=60"
    # the server's own prefix is replaced, not repeated
    env["FBS_PREFIX"] = "/tire-fbs/"
    assert public_link("http://127.0.0.1:5006/tire-fbs/main?h=2", env) == BASE + "/main?h=2"
    assert public_link("http://127.0.0.1:5006/tire-fbsx/main", env) == BASE + "/tire-fbsx/main"
    assert public_link("http://localhost:5006/main", {}) == "http://localhost:5006/main"


def _entrypoint():
    spec = importlib.util.spec_from_file_location(
        "fbs_entry_pub", ROOT / "docker" / "entrypoint.py"
    )
    mod = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = mod  # (its dataclass looks the module up)
    assert spec.loader is not None
    spec.loader.exec_module(mod)
    return mod


def test_the_entrypoint_refuses_an_invalid_public_url_before_the_server_starts(tmp_path):
    entry = _entrypoint()
    app = tmp_path / "a.py"
    app.write_text("")
    with pytest.raises(entry.SettingError, match=r"FBS_PUBLIC_URL='localhost:5006'.*http"):
        entry.build_launch({"FBS_APP": str(app), "FBS_PUBLIC_URL": "localhost:5006"}, [])
    entry.build_launch({"FBS_APP": str(app), "FBS_PUBLIC_URL": BASE}, [])  # accepted


def _links(text: str) -> list[str]:
    return [u for u in re.findall(r"https?://[^\s\"'<>)]+", text) if not u.startswith(NAMESPACES)]


def test_every_link_of_reports_csv_and_title_blocks_starts_with_the_public_url(monkeypatch):
    import panel as pn
    from pypdf import PdfReader

    from app.export import read_csv, to_csv
    from app.page.titles import page_url, view_title
    from app.report import build_html, build_pdf
    from app.report.session import report_data
    from app.store import Results
    from app.views.live import export_meta

    class Loc:  # what page_url reads of Panel's Location
        href = "http://localhost:5006/tire-fbs/main?h=3&N=40"
        query_params = {"h": 3, "N": 40}

    loc = Loc()
    monkeypatch.setattr(type(pn.state), "location", property(lambda self: loc))
    monkeypatch.setenv("FBS_PUBLIC_URL", BASE)
    monkeypatch.setenv("FBS_PREFIX", "tire-fbs")
    url = page_url()
    assert url == BASE + "/main?h=3&N=40"

    res = Results()
    try:
        res.state.case.param.update(harmonic=3, n_modes=40)
        res.state.noise.rounds = 30
        data = report_data(res, url=page_url())
        _, html = build_html(data)
        hrefs = [h for h in re.findall(r'href="([^"]*)"', html) if not h.startswith(("#", "data:"))]
        assert hrefs and all(h.startswith(BASE) for h in hrefs)
        links = _links(html)
        assert links and all(u.startswith(BASE) for u in links), links
        _, pdf = build_pdf(data)
        text = "\n".join(p.extract_text() for p in PdfReader(io.BytesIO(pdf)).pages)
        links = _links(text)
        assert links and all(u.startswith(BASE) for u in links), links
        for name in ("response", "error_map", "band_curves"):
            r = getattr(res, name)
            csv = to_csv(r.columns, export_meta(r.meta), name)
            meta, _ = read_csv(csv)
            assert meta["page URL"] == url
            header = "\n".join(ln for ln in csv.splitlines() if ln.startswith("#"))
            assert _links(header) and all(u.startswith(BASE) for u in _links(header))
            tb, _ = view_title("mobility", r.snapshot, page_url())
            assert any(BASE in line for line in tb.lines)
            assert all(u.startswith(BASE) for line in tb.lines for u in _links(line))
    finally:
        res.close()
