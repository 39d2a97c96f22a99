"""The landmark table in the dashboard (issue 14): read-only, from data/landmarks.json.

Truth: the shipped table must be what fbs_core.tire.landmarks measures on the shipped
reference tire (a stale file fails), and the card shows every landmark and mechanism row.
"""

import json

import panel as pn

from app.views.landmarks import (
    LABELS,
    LANDMARKS_FILE,
    landmarks_card,
    landmarks_markdown,
    load_landmarks,
)
from fbs_core.tire.landmarks import THESIS, landmarks


def test_shipped_table_is_the_shipped_tire_measured():
    data = load_landmarks()
    lm = data["landmarks"]
    assert lm["keys"] == list(THESIS)
    measured = [v for _, v in landmarks().rows()]  # the shipped reference tire
    assert lm["columns"]["reference"] == measured
    ref = data["mechanisms"]["rows"]["loaded (reference)"]
    assert ", ".join(map(str, ref["table_160"])) == measured[lm["keys"].index("table_5_1_160")]


def test_card_shows_every_row(tmp_path):
    data = load_landmarks()
    text = landmarks_markdown(data)
    for key in data["landmarks"]["keys"]:
        assert LABELS[key] in text
    for name in data["mechanisms"]["rows"]:
        assert f"| {name} |" in text
    card = landmarks_card()
    assert isinstance(card, pn.Card) and card.collapsed
    # a missing or old file is reported in the card, not raised into the page
    bad = tmp_path / "landmarks.json"
    bad.write_text(json.dumps({"landmarks": {}}), encoding="utf-8")
    try:
        load_landmarks(bad)
        raise AssertionError("an incomplete file must be rejected")
    except ValueError as exc:
        assert "mechanisms" in str(exc)
    assert LANDMARKS_FILE.name == "landmarks.json"


def test_page_has_the_card():
    from app.main import create_app

    app = create_app()
    cards = [c for c in app.main[0].select(pn.Card) if "landmarks-card" in c.css_classes]
    assert len(cards) == 1 and cards[0].collapsed
