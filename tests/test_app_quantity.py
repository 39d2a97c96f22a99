"""An uploaded chassis FRF whose file does not say what it holds: the page asks for the
quantity (no Python hint), and with the quantity chosen the upload is read and used."""

from __future__ import annotations

import re

import numpy as np
import pytest

import fbs_core
from app.datasource import DataSource
from fbs_core.io.csv import write_csv

GRID = np.arange(13.0, 422.01, 0.5)


@pytest.fixture(scope="module")
def unlabelled_csv():
    """The reference chassis mobility as CSV without its quantity or any unit."""
    text = write_csv(fbs_core.reference_chassis().mobility(GRID)).decode()
    lines = [ln for ln in text.splitlines() if not ln.startswith(("# quantity", "# units"))]
    i = next(k for k, ln in enumerate(lines) if ln.startswith("freq"))
    lines[i] = "freq [Hz]," + re.sub(r" \[[^\]]*\]", "", lines[i].split(",", 1)[1])
    return ("\n".join(lines) + "\n").encode()


def test_a_file_without_its_quantity_asks_for_it_on_the_page(unlabelled_csv):
    ds = DataSource()
    assert not ds.load_chassis(unlabelled_csv, "chassis.csv")
    assert ds.models.is_reference
    assert "pass quantity" not in ds.error
    assert "'Quantity'" in ds.error and "receptance, mobility or accelerance" in ds.error


def test_the_chosen_quantity_reads_the_file_as_that_quantity(unlabelled_csv):
    ds = DataSource()
    assert not ds.load_chassis(unlabelled_csv, "chassis.csv")
    ds.quantity = "mobility"  # the page re-reads the last upload with the new choice
    assert ds.reread_if_changed() is True, ds.error
    assert not ds.models.is_reference and ds.error == ""
    f = fbs_core.harmonic(3).frequencies()
    want = fbs_core.bushing_response(harmonic=3, n_modes=60, freq=f)
    got = fbs_core.bushing_response(harmonic=3, n_modes=60, freq=f, chassis=ds.models.chassis)
    # the file holds the reference chassis' mobility: the coupled response is the reference
    np.testing.assert_allclose(got.data, want.data, rtol=1e-9, atol=0)
    # read as a receptance it is another chassis (i omega times the mobility): not equal
    ds.quantity = "receptance"
    assert ds.reread_if_changed() is True, ds.error
    other = fbs_core.bushing_response(harmonic=3, n_modes=60, freq=f, chassis=ds.models.chassis)
    assert np.max(np.abs(other.data - want.data) / np.abs(want.data)) > 0.5
