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

Every finished task is a *unit* (a group with attribute ``unit = 1``). A unit is first
written as its own small HDF5 file in ``<output>.parts/`` (written to a temporary name,
flushed and renamed: atomic), and :meth:`CampaignStore.commit` merges the parts into a
copy of the result file and renames the copy over it (atomic again) before deleting the
merged parts. A run killed at any moment therefore leaves the result file as it was at
the last commit plus complete parts; the next run (or :func:`open_campaign`) sees both.
(Parts are not fsynced one by one: after a power cut, as opposed to a killed process,
the parts since the last commit may be lost and are recomputed.)
"""

from __future__ import annotations

import hashlib
import json
import os
import shutil
import time
from pathlib import Path
from typing import TYPE_CHECKING, Any, TypeAlias

import numpy as np

from .spec import CampaignError

if TYPE_CHECKING:
    from .spec import Campaign

#: An h5py File, Group or Dataset (h5py ships no type stubs).
H5: TypeAlias = Any

__all__ = ["CampaignStore", "FORMAT_VERSION"]

FORMAT_VERSION = 1


def _now() -> str:
    return time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())


def file_sha256(path: str | os.PathLike[str]) -> str:
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for b in iter(lambda: f.read(1 << 20), b""):
            h.update(b)
    return h.hexdigest()


def _set_attrs(obj: H5, attrs: dict[str, Any]) -> None:
    for k, v in attrs.items():
        if isinstance(v, bool | int | float | str | np.integer | np.floating):
            obj.attrs[k] = v
        elif v is None:
            obj.attrs[k] = "none"
        else:
            obj.attrs[k] = json.dumps(v, default=str)


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
    """Copy what ``dst`` lacks from ``src``: attributes, datasets, whole units."""
    import h5py

    for k, v in src.attrs.items():
        if k not in dst.attrs:
            dst.attrs[k] = v
    for name, obj in src.items():
        if name in dst:
            if isinstance(obj, h5py.Group) and not _is_unit(obj):
                _merge(obj, dst[name])
            continue
        if isinstance(obj, h5py.Dataset) or _is_unit(obj):
            src.copy(obj, dst, name=name)
        else:
            _merge(obj, dst.create_group(name))


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
        import h5py

        out: set[str] = set()
        for p in self.files():
            try:
                with h5py.File(p, "r") as h:
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
        import h5py

        self.parts.mkdir(parents=True, exist_ok=True)
        final = self.parts / (path.replace("/", "__") + ".h5")
        tmp = final.with_name(final.name + f".{os.getpid()}.tmp")
        with h5py.File(tmp, "w") as h:
            for ppath, pattrs in (parents or {}).items():
                _set_attrs(h.require_group(ppath), pattrs)
            g = h.require_group(path)
            for k, v in data.items():
                _put(g, k, v)
            _set_attrs(g, {**attrs, "unit": 1, "finished": _now()})
        # the rename is atomic for a killed process; no fsync per task (it cost 30-50 ms on
        # a busy disk, the client's whole budget per task): a power cut may lose the parts
        # since the last commit, which fsyncs the result file
        os.replace(tmp, final)
        return final

    def commit(self, root_attrs: dict[str, Any] | None = None) -> int:
        """Merge the parts into the result file (atomically); returns the units merged."""
        import h5py

        parts = self._part_files()
        if not parts and (self.output.is_file() or root_attrs is None):
            return 0
        tmp = self.output.with_name(self.output.name + f".{os.getpid()}.tmp")
        if self.output.is_file():
            shutil.copyfile(self.output, tmp)
        n = 0
        try:
            with h5py.File(tmp, "a") as h:
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

                _set_attrs(h, {**(root_attrs or {}), "fbs_core_version": __version__})
                h.attrs["updated"] = _now()
                for p in parts:
                    with h5py.File(p, "r") as src:
                        n += len(_units(src))
                        _merge(src, h)
            with open(tmp, "rb+") as f:
                os.fsync(f.fileno())
            os.replace(tmp, self.output)
        finally:
            if tmp.exists():
                tmp.unlink()
        for p in parts:
            p.unlink()
        for p in self.parts.glob("*.tmp") if self.parts.is_dir() else ():
            p.unlink()  # a write interrupted before its rename
        if self.parts.is_dir() and not any(self.parts.iterdir()):
            self.parts.rmdir()
        return n

    def unit_attrs(self, path: str) -> dict[str, Any] | None:
        """Attributes of a stored unit (result file or parts), None when absent."""
        import h5py

        for p in self.files():
            with h5py.File(p, "r") as h:
                if path in h:
                    return {k: v for k, v in h[path].attrs.items()}
        return None

    # -- checks ------------------------------------------------------------------------------
    def case_digests(self) -> dict[str, str]:
        """``case name -> settings digest`` of the cases already in the file or parts."""
        import h5py

        out: dict[str, str] = {}
        for p in self.files():
            with h5py.File(p, "r") as h:
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
        import h5py

        if self.output.is_file():
            try:
                with h5py.File(self.output, "r") as h:
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
