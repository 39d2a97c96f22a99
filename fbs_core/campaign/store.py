"""The result file of a campaign: one HDF5 file, written task by task, resumable.

Layout (all groups carry their settings as attributes; ``settings`` is JSON text)::

    /                                   format = "tire-fbs", content = "campaign",
                                        format_version, fbs_core_version, created,
                                        updated, campaign_name, campaign_seed, seeds,
                                        campaign_toml (the campaign file's text)
    /models/{tire,chassis}/<variant>    source ("reference" or path), sha256 of the file
    /inputs/<id>/                       freq, YjjA, vj, YjjE, YejE, reference; dofs,
                                        harmonic, n_modes, n_modes_total, coupling, ...
    /cases/<case>/                      kind, settings, digest, seed, n_lines, inputs
    /cases/<case>/blocks/<l0>_<l1>/     lower, upper, argmin_round, argmax_round,
                                        percentiles, conv_lower, conv_upper, checkpoints;
                                        worker, host, pid, seconds, finished (UTC)
    /cases/<case>/result/               truncation case: n_modes, centres, error,
                                        suggested, [freq, response, reference]
    /runs/<started>/                    one record per run: scheduler, workers, versions,
                                        tasks done, status

Every finished task is a *unit* (a group with attribute ``unit = 1``). Units are first
written as a small HDF5 file in ``<output>.parts/``, a *part* (written to a temporary name,
flushed and renamed: atomic); a part holds one unit or several (the blocks of one cluster
task, :meth:`CampaignStore.write_units`: all of them or none). :meth:`CampaignStore.commit`
merges the parts into a copy of the result file and renames the copy over it (atomic
again) before deleting the merged parts; during a run, :class:`Merging` keeps that copy
open and merges each part as it is written, so that the end of the run has little left
to merge. A run killed at any moment therefore leaves the result file as it was at the
last commit plus complete parts (and maybe a stale copy, deleted by the next commit); the
next run (or :func:`open_campaign`) sees both. (Parts are not fsynced one by one: after a
power cut, as opposed to a killed process, the parts since the last commit may be lost
and are recomputed.)
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import time
from collections.abc import Iterator, Sequence
from contextlib import ExitStack, contextmanager
from pathlib import Path
from typing import TYPE_CHECKING, Any

import numpy as np

from ..errors import CampaignError
from ..hdf5_guard import open_h5

if TYPE_CHECKING:
    from .spec import Campaign

#: An h5py File, Group or Dataset (h5py ships no type stubs).
type H5 = Any

#: A finished unit to write: ``(path, data, attrs, parents)``, see
#: :meth:`CampaignStore.write_unit`.
type Unit = tuple[str, dict[str, Any], dict[str, Any], dict[str, dict[str, Any]] | None]

__all__ = ["CampaignStore", "FORMAT_VERSION"]

FORMAT_VERSION = 1


@contextmanager
def read_file(path: Path) -> Iterator[H5]:
    """A result file or part opened for reading through :func:`fbs_core.hdf5_guard.open_h5`
    (a file linking to, or mapping data from, other files is refused).

    Raises
    ------
    CampaignError
        For a file that is not HDF5, or that points outside itself (naming the object).
    """
    with ExitStack() as stack:
        try:
            h = stack.enter_context(open_h5(path, error=CampaignError))
        except OSError as e:
            raise CampaignError(f"{path}: not a readable HDF5 file ({e})") from None
        yield h


def _now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())


def file_sha256(path: str | os.PathLike[str]) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for b in iter(lambda: f.read(1 << 20), b""):
            h.update(b)
    return h.hexdigest()


def _set_attrs(obj: H5, attrs: dict[str, Any]) -> None:
    a = obj.attrs  # (h5py makes a new attribute manager on every access)
    for k, v in attrs.items():
        if isinstance(v, bool | int | float | str | np.integer | np.floating):
            a[k] = v
        elif v is None:
            a[k] = "none"
        else:
            a[k] = json.dumps(v, default=str)


def _put(g: H5, name: str, v: Any) -> None:
    import h5py

    a = np.asarray(v)
    if a.dtype.kind in "UO":
        g.create_dataset(name, data=a.astype(object), dtype=h5py.string_dtype())
    else:
        g.create_dataset(name, data=a)


def _is_unit(obj: H5) -> bool:
    return int(obj.attrs.get("unit", 0)) == 1


def _merge(src: H5, dst: H5) -> None:
    """Copy what ``dst`` lacks from ``src``: attributes, datasets, whole units, whole groups
    (an object ``dst`` lacks is copied with all it holds, by HDF5 itself)."""
    import h5py

    sa, da = src.attrs, dst.attrs
    for k in sa:
        if k not in da:
            da[k] = sa[k]
    for name in src:
        if name not in dst:
            src.copy(name, dst, name=name)
            continue
        obj = src[name]
        if isinstance(obj, h5py.Group) and not _is_unit(obj):
            _merge(obj, dst[name])


def _units(h: H5, prefix: str = "") -> set[str]:
    import h5py

    out: set[str] = set()
    for name, obj in h.items():
        if isinstance(obj, h5py.Group):
            p = f"{prefix}{name}"
            if _is_unit(obj):
                out.add(p)
            else:
                out |= _units(obj, p + "/")
    return out


class CampaignStore:
    """Writer and journal of one campaign result file.

    Parameters
    ----------
    output : path
        The HDF5 result file; the journal of finished tasks is ``<output>.parts/``.
    """

    def __init__(self, output: str | os.PathLike[str]) -> None:
        self.output = Path(output)
        self.parts = self.output.with_name(self.output.name + ".parts")

    # -- journal -----------------------------------------------------------------------------
    def _part_files(self) -> list[Path]:
        if not self.parts.is_dir():
            return []
        return sorted(p for p in self.parts.iterdir() if p.suffix == ".h5")

    def files(self) -> list[Path]:
        """The result file (if any) and the parts not merged yet, in this order."""
        return ([self.output] if self.output.is_file() else []) + self._part_files()

    def done(self) -> set[str]:
        """Paths of all finished units (result file and parts)."""

        out: set[str] = set()
        for p in self.files():
            try:
                with open_h5(p, error=CampaignError) as h:
                    out |= _units(h)
            except OSError as e:
                if p == self.output:
                    raise CampaignError(f"{p}: not a readable HDF5 result file ({e})") from None
                p.unlink()  # a part is complete or absent (renamed atomically); never here
        return out

    def write_unit(
        self,
        path: str,
        data: dict[str, Any],
        attrs: dict[str, Any],
        parents: dict[str, dict[str, Any]] | None = None,
    ) -> Path:
        """Write one finished task atomically as a part file.

        Parameters
        ----------
        path : str
            Group path of the unit, e.g. ``cases/<case>/blocks/0_80``.
        data : dict of str to array_like
            Datasets of the unit.
        attrs : dict
            Attributes of the unit (numbers, text; anything else stored as JSON).
        parents : dict of str to dict, optional
            Attributes of parent groups (e.g. the case's settings).
        """
        return self.write_units([(path, data, attrs, parents)])

    def write_units(self, units: Sequence[Unit]) -> Path:
        """Write finished units atomically as one part file: all of them or none.

        Parameters
        ----------
        units : sequence of (path, data, attrs, parents)
            As the arguments of :meth:`write_unit` (a parent's attributes are written once
            per part file, by its first unit).

        Returns
        -------
        Path
            The part file.
        """
        import h5py

        if not units:
            raise ValueError("no units to write")
        self.parts.mkdir(parents=True, exist_ok=True)
        name = units[0][0].replace("/", "__") + (f"+{len(units) - 1}" if len(units) > 1 else "")
        final = self.parts / (name + ".h5")
        tmp = final.with_name(final.name + f".{os.getpid()}.tmp")
        finished = _now()
        with h5py.File(tmp, "w") as h:
            seen: set[str] = set()
            for path, data, attrs, parents in units:
                for ppath, pattrs in (parents or {}).items():
                    if ppath not in seen:
                        seen.add(ppath)
                        _set_attrs(h.require_group(ppath), pattrs)
                g = h.require_group(path)
                for k, v in data.items():
                    _put(g, k, v)
                _set_attrs(g, {**attrs, "unit": 1, "finished": finished})
        # the rename is atomic for a killed process; no fsync per task (it cost 30-50 ms on
        # a busy disk, the client's whole budget per task): a power cut may lose the parts
        # since the last commit, which fsyncs the result file
        os.replace(tmp, final)
        return final

    def commit(self, root_attrs: dict[str, Any] | None = None) -> int:
        """Merge the parts into the result file (atomically); returns the units merged."""
        parts = self._part_files()
        if not parts and (self.output.is_file() or root_attrs is None):
            return 0
        merge = self.merging(root_attrs)
        for p in parts:
            merge.merge(p)  # a failure drops the copy: the file and the parts as they were
        return merge.finish(rest=False)

    def merging(self, root_attrs: dict[str, Any] | None = None) -> Merging:
        """A copy of the result file, open, into which parts are merged as they are written
        (see :class:`Merging`)."""
        return Merging(self, root_attrs)

    def unit_attrs(self, path: str) -> dict[str, Any] | None:
        """Attributes of a stored unit (result file or parts), None when absent."""

        for p in self.files():
            with read_file(p) as h:
                if path in h:
                    return {k: v for k, v in h[path].attrs.items()}
        return None

    # -- checks ------------------------------------------------------------------------------
    def case_digests(self) -> dict[str, str]:
        """``case name -> settings digest`` of the cases already in the file or parts."""

        out: dict[str, str] = {}
        for p in self.files():
            with read_file(p) as h:
                for name, g in h.get("cases", {}).items():
                    if "digest" in g.attrs:
                        out.setdefault(name, str(g.attrs["digest"]))
        return out

    def check(self, campaign: Campaign) -> None:
        """Refuse to mix results of different settings under the same case name.

        Raises
        ------
        CampaignError
            When the file holds a case of the same name computed with other settings
            (seed, percentiles, grid ...), or is another tool's file.
        """

        if self.output.is_file():
            try:
                with open_h5(self.output, error=CampaignError) as h:
                    if h.attrs.get("content") != "campaign":
                        raise CampaignError(
                            f"{self.output} exists and is not a campaign result file; "
                            "choose another output"
                        )
            except OSError as e:
                raise CampaignError(f"{self.output}: not a readable HDF5 file ({e})") from None
        have = self.case_digests()
        for c in campaign.cases:
            d = have.get(c.name)
            if d is not None and d != c.digest():
                raise CampaignError(
                    f"{self.output} holds case {c.name} computed with other settings "
                    f"(seed, percentiles, grid or model); write to a new output file or "
                    f"restore the campaign file it was made with (stored in the file)"
                )


class Merging:
    """The result file being merged while a run goes on.

    A copy of the result file (in the parts folder, ``*.tmp``) is opened and every part
    :meth:`add`-ed is merged into it at once, while the workers compute, so that
    :meth:`finish` has only the parts not added yet to merge before it closes the copy,
    fsyncs it and renames it over the result file (atomic), and deletes the parts merged.
    The parts stay on disk until then: a run killed at any moment leaves the result file as
    it was and all the parts (the next commit deletes the stale copy). When a merge into the
    copy fails (or is interrupted), the copy is dropped and :meth:`finish` merges all parts
    afresh (:meth:`CampaignStore.commit`).

    Parameters
    ----------
    store : CampaignStore
    root_attrs : dict, optional
        Attributes of the file's root (the campaign's name, seed, text ...).
    """

    def __init__(self, store: CampaignStore, root_attrs: dict[str, Any] | None = None) -> None:
        import h5py

        self.store, self.root_attrs = store, root_attrs
        store.parts.mkdir(parents=True, exist_ok=True)
        self.tmp = store.parts / f"{store.output.name}.{os.getpid()}.tmp"
        self.merged: list[Path] = []
        self.units = 0
        if store.output.is_file():
            shutil.copyfile(store.output, self.tmp)  # over a killed run's copy of this pid
            self._h: H5 | None = h5py.File(self.tmp, "a")
        else:
            self._h = h5py.File(self.tmp, "w")
        try:
            self._root(self._h)
        except BaseException:
            self.abort()
            raise

    def _root(self, h: H5) -> None:
        if "format" not in h.attrs:
            _set_attrs(
                h,
                {
                    "format": "tire-fbs",
                    "content": "campaign",
                    "format_version": FORMAT_VERSION,
                    "created": _now(),
                },
            )
        from .. import __version__

        _set_attrs(h, {**(self.root_attrs or {}), "fbs_core_version": __version__})

    @property
    def broken(self) -> bool:
        """Whether the copy was dropped (a merge into it failed)."""
        return self._h is None

    def add(self, part: Path) -> bool:
        """Merge one part file into the copy; False when the copy is (or is now) dropped.

        A failing merge drops the copy and is not the run's failure: the part is on disk and
        :meth:`finish` merges all parts afresh. An interrupt (KeyboardInterrupt) drops the
        copy too and is raised.
        """
        if self._h is None:
            return False
        try:
            self.merge(part)
        except Exception:
            return False
        return True

    def merge(self, part: Path) -> None:
        """Merge one part file into the copy; on any failure the copy is dropped and the
        error raised."""

        if self._h is None:
            raise CampaignError(f"{self.tmp}: the copy of the result file was dropped")
        try:
            with read_file(part) as src:
                n = len(_units(src))
                _merge(src, self._h)
        except BaseException:
            self.abort()
            raise
        self.units += n
        self.merged.append(part)

    def abort(self) -> None:
        """Drop the copy (the result file and the parts stay as they are)."""
        h, self._h = self._h, None
        try:
            if h is not None:
                h.close()
        finally:
            self.tmp.unlink(missing_ok=True)

    def finish(self, rest: bool = True) -> int:
        """Merge the parts not added yet (``rest``), make the copy the result file, delete the
        merged parts; returns the units merged by this object."""
        if self._h is None:
            return self.store.commit(self.root_attrs)
        if rest:
            done = set(self.merged)
            for p in self.store._part_files():
                if p not in done and not self.add(p):
                    return self.store.commit(self.root_attrs)
        try:
            h = self._h
            h.attrs["updated"] = _now()
            self._h = None
            h.close()
            with open(self.tmp, "rb+") as f:
                os.fsync(f.fileno())
            os.replace(self.tmp, self.store.output)
        except BaseException:
            self.abort()
            raise
        self._clean()
        return self.units

    def _clean(self) -> None:
        parts = self.store.parts
        for p in self.merged:
            p.unlink()
        for p in parts.glob("*.tmp"):
            p.unlink()  # a write interrupted before its rename, a killed run's copy
        if not any(parts.iterdir()):
            parts.rmdir()
