"""A link with a value the dashboard cannot read opens a page with a message naming the key.

Served as the container serves it (``docker/entrypoint.py``, the dashboard ``app/main.py``):
Panel reads every value of the query when a page first asks for its location, and a value
of more than 4,300 digits stopped it with a ``ValueError`` (Python's limit for ``int()``):
a blank page and a traceback in the server's log. Now such a link, one with a key or value
longer than any setting holds, or bytes that are not UTF-8, opens a page that names each
key and why, links to the dashboard without them, and logs one line, no traceback; a link
with readable values (also 1,000-character ones) still opens the dashboard.
"""

from __future__ import annotations

import html
import json
import re
import sys
import urllib.parse
import urllib.request

import pytest
from server_util import NoRedirect, Server, get, run_async, websocket_session

from app.page.query import MAX_QUERY_CHARS, kept_query, unreadable_keys, unreadable_link_html


def _strings(node) -> list[str]:
    if isinstance(node, str):
        return [node]
    if isinstance(node, dict):
        return [s for v in node.values() for s in _strings(v)]
    if isinstance(node, list):
        return [s for v in node for s in _strings(v)]
    return []


@pytest.fixture(scope="module")
def dashboard(tmp_path_factory):
    srv = Server(tmp_path_factory.mktemp("unreadable"), None, {})
    try:
        yield srv.started(600)
    finally:
        srv.stop()


def _open(srv: Server, query: str) -> tuple[str, str]:
    """(the page's text as shown, the server's log while it was opened) of ``/main?query``."""
    log0 = len(srv.log())
    status, _, body = get(urllib.request.build_opener(NoRedirect), f"{srv.base}/main?{query}")
    token = re.search(r'"token":\s*"([^"]+)"', body)
    assert status == 200 and token, (status, body[:500], srv.log()[log0:][-3000:])
    _, content = run_async(websocket_session(srv.port, "main", None, token.group(1)))
    text = "\n".join(html.unescape(s) for s in _strings(json.loads(content)))
    return text, srv.log()[log0:]


@pytest.mark.parametrize(
    ("query", "key", "why"),
    [
        ("h=" + "9" * 5_000 + "&N=100", "'h'", "5,000 digits (at most 4,300"),
        ("N=100&zz=" + "7" * 4_301, "'zz'", "4,301 digits"),
        ("h=3&pins=" + "x~h1|" * 1_000, "'pins'", "5,000 characters (at most 4,000"),
        ("dof=%FF%FE&N=100", "'dof'", "not UTF-8 text"),
    ],
)
def test_an_unreadable_value_opens_a_page_naming_its_key(dashboard, query, key, why):
    text, log = _open(dashboard, query)
    assert "This link cannot be opened" in text, text[:2000]
    plain = html.unescape(re.sub(r"<[^>]+>", "", text))  # the text as the browser shows it
    assert f"{key}: its value" in plain and why in plain, text[:2000]
    # the link to the dashboard keeps the readable settings
    kept = [k for k in ("h=3", "N=100") if k in query]
    assert re.search(r'href="/main\?' + "&".join(kept), text), text[:2000]
    assert "Traceback" not in log and "Error running application handler" not in log, log[-3000:]
    assert "unreadable query values" in log


def test_readable_values_still_open_the_dashboard(dashboard):
    """The control: long readable values (the fuzz's 1,000 characters) and a setting."""
    text, log = _open(dashboard, "h=3&cmp=" + "A" * 1_000 + "&data=" + "b" * 1_000)
    assert "This link cannot be opened" not in text
    assert "mobility.reference" in text  # the coupled response's data source
    assert "Traceback" not in log


# ---- the check on its own --------------------------------------------------------------------


def test_unreadable_keys_names_each_key_and_why():
    limit = sys.get_int_max_str_digits()
    args = {
        "h": [b"9" * (limit + 1)],
        "N": [b"9" * min(limit, MAX_QUERY_CHARS)],  # readable: at the limits
        "x" * (MAX_QUERY_CHARS + 1): [b"1"],
        "dof": [b"\xff"],
        "pins": [b"ok", b"a" * (MAX_QUERY_CHARS + 1)],
        "cmp": [b"a" * MAX_QUERY_CHARS],
        "\u00c3\u00a9": [b"1"],  # a UTF-8 key as Tornado hands it over (Latin-1): readable
    }
    bad = unreadable_keys(args)
    assert set(bad) == {"h", "x" * (MAX_QUERY_CHARS + 1), "dof", "pins"}
    assert bad["h"] == f"its value has {limit + 1:,} digits (at most {limit:,} are read)"
    assert bad["dof"] == "its value is not UTF-8 text"
    assert bad["pins"].startswith("a value has")
    assert bad["x" * (MAX_QUERY_CHARS + 1)].startswith("the key has")
    kept = kept_query(args, list(bad))
    assert urllib.parse.parse_qsl(kept[1:]) == [
        ("N", "9" * min(limit, MAX_QUERY_CHARS)),
        ("cmp", "a" * MAX_QUERY_CHARS),
        ("\u00e9", "1"),
    ]


def test_the_message_repeats_no_markup_of_the_link():
    key = '<img src=x onerror=alert(1)>"'
    page = unreadable_link_html({key: "its value is not UTF-8 text"}, '?a="><b>', "/main")
    assert "<img" not in page and "&lt;img" in page
    assert 'href="/main?a=&quot;&gt;&lt;b&gt;"' in page
