"""What a sweep writes to its folder: the per-sample table, the worst cases as specs, the JSON and the report.

Every file is written to a temporary name and renamed into place, so a file is complete or absent.
"""

from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

from designkit.errors import OutputError

__all__ = ["write_outputs"]


def _atomic(path: Path, data: str | bytes) -> None:
    tmp = path.with_name(f".{path.name}.{os.getpid()}.tmp")
    if isinstance(data, bytes):
        tmp.write_bytes(data)
    else:
        tmp.write_text(data, encoding="utf-8")
    os.replace(tmp, path)


def write_outputs(result: Any, prep: Any, folder: Path, *, report: bool = True) -> dict[str, str]:
    """Write ``samples.csv``, ``worst/<name>-worst-<k>.yaml``, ``sweep.json`` and (``report``) ``report.html`` and
    ``report.pdf`` into ``folder``; return their paths by role (``samples``, ``worst_<k>``, ``json``, ``html``,
    ``pdf``).

    Raises
    ------
    OutputError
        ``--out`` not writable.
    """
    files: dict[str, str] = {}
    try:
        (folder / "worst").mkdir(parents=True, exist_ok=True)
        path = folder / "samples.csv"
        _atomic(path, result.table.to_csv(index=False, float_format="%.10g"))
        files["samples"] = str(path)
        for w in result.worst:
            path = folder / "worst" / f"{result.name}-worst-{w.rank}.yaml"
            _atomic(path, w.spec_text)
            files[f"worst_{w.rank}"] = str(path)
        if report:
            import dataclasses

            from designkit.sweep.report import build_report, html_text, pdf_bytes

            named = dataclasses.replace(result, worst=tuple(dataclasses.replace(w, spec_file=files[f"worst_{w.rank}"])
                                                            for w in result.worst))
            rep = build_report(named, prep)
            _atomic(folder / "report.html", html_text(rep))
            files["html"] = str(folder / "report.html")
            _atomic(folder / "report.pdf", pdf_bytes(rep))
            files["pdf"] = str(folder / "report.pdf")
        files["json"] = str(folder / "sweep.json")
        payload = result.to_json()
        payload["files"] = dict(files)
        _atomic(folder / "sweep.json", json.dumps(payload, indent=2, allow_nan=False, default=_plain))
    except OSError as exc:
        raise OutputError("--out", f"cannot write to {folder}: {exc.strerror or exc}") from None
    return files


def _plain(value: Any) -> Any:
    import numpy as np

    if isinstance(value, np.generic):
        return value.item()
    raise TypeError(type(value).__name__)
