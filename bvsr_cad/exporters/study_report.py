"""A design study's files: the results table (Parquet and CSV), the plots and ``report.html``.

Written from the rows :mod:`bvsr_cad.studies.sweep` collected, one per variant. Every
file is written to a temporary name and renamed, so an interrupted write never
leaves half a table. The report plots every numeric metric against every axis
(one line per combination of the other axes), an Optuna study's history and its
Pareto front, and checks each trend the study file expects against the results
(the sign of a rank correlation over the variants that ran), beside its source.
"""

from __future__ import annotations

import html
import math
import os
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from .plots import plt

SKIP = {"key", "label", "status", "reason", "worker", "trial", "failed_checks", "checks_json"}


def toml_text(data: dict[str, Any]) -> str:
    """A parameter mapping as TOML (scalars first, then one [table] per nested table)."""
    lines: list[str] = []

    def value(v: Any) -> str:
        if isinstance(v, bool):
            return "true" if v else "false"
        if isinstance(v, (int, float)):
            return repr(v) if not isinstance(v, float) or math.isfinite(v) else str(v)
        if isinstance(v, str):
            return '"' + v.replace("\\", "\\\\").replace('"', '\\"') + '"'
        if isinstance(v, list):
            return "[" + ", ".join(value(x) for x in v) + "]"
        if isinstance(v, dict):
            return "{ " + ", ".join(f"{_key(k)} = {value(x)}" for k, x in v.items()) + " }"
        raise TypeError(f"cannot write {v!r} as TOML")

    def table(node: dict[str, Any], prefix: str) -> None:
        scalars = {k: v for k, v in node.items() if not isinstance(v, dict)}
        tables = {k: v for k, v in node.items() if isinstance(v, dict)}
        if prefix and (scalars or not tables):
            lines.append(f"\n[{prefix}]")
        for k, v in scalars.items():
            lines.append(f"{_key(k)} = {value(v)}")
        for k, v in tables.items():
            table(v, f"{prefix}.{_key(k)}" if prefix else _key(k))

    table(data, "")
    return "\n".join(lines).lstrip("\n") + "\n"


def _key(k: str) -> str:
    return k if k.replace("_", "").replace("-", "").isalnum() else f'"{k}"'


def _atomic(path: Path, write) -> None:
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def _frame(study, rows: list[dict[str, Any]]):
    import pandas as pd

    df = pd.DataFrame(rows)
    first = ["key", "label", "status", "reason", *[a for a in study.axes if a in df.columns]]
    if "trial" in df.columns:
        first.insert(1, "trial")
    rest = [c for c in df.columns if c not in first]
    df = df[[c for c in first if c in df.columns] + rest]
    for (
        col
    ) in df.columns:  # one type per column (Parquet): a column mixing text and numbers becomes text
        values = df[col].dropna()
        if (
            df[col].dtype == object
            and values.map(lambda v: isinstance(v, str)).any()
            and not values.map(lambda v: isinstance(v, str)).all()
        ):
            df[col] = df[col].map(
                lambda v: None if v is None or (isinstance(v, float) and math.isnan(v)) else str(v)
            )
    return df


def write_outputs(study, rows: list[dict[str, Any]], out: Path) -> dict[str, str]:
    """``results.parquet``, ``results.csv``, ``plots/*.png`` and ``report.html`` in ``out``."""
    df = _frame(study, rows)
    files = {}
    for name, write in (
        ("results.parquet", lambda p: df.to_parquet(p, index=False)),
        ("results.csv", lambda p: df.to_csv(p, index=False)),
    ):
        _atomic(out / name, write)
        files[name] = str(out / name)
    plots = out / "plots"
    plots.mkdir(exist_ok=True)
    images = _metric_plots(study, df, plots)
    if study.kind == "optuna":
        images += _optuna_plots(study, df, plots)
    trends = expectations(study, df)
    _atomic(
        out / "report.html",
        lambda p: Path(p).write_text(_html(study, df, images, trends), encoding="utf-8"),
    )
    files["report.html"] = str(out / "report.html")
    return files


def _numeric(df, col) -> bool:
    import pandas as pd

    return (
        col in df.columns
        and pd.api.types.is_numeric_dtype(df[col])
        and not pd.api.types.is_bool_dtype(df[col])
    )


def _metrics(study, df) -> list[str]:
    return [
        c
        for c in df.columns
        if c not in SKIP
        and c not in study.axes
        and not c.startswith(("seconds", "fitted_"))
        and _numeric(df, c)
        and df[c].notna().any()
    ]


def _metric_plots(study, df, folder: Path) -> list[tuple[str, str]]:
    ok = df[df["status"] == "ok"]
    axes = [a for a in study.axes if a in ok.columns]
    if ok.empty or not axes:
        return []
    out = []
    for metric in _metrics(study, ok):
        fig, subplots = plt.subplots(1, len(axes), figsize=(5.2 * len(axes), 3.8), squeeze=False)
        for ax, axis in zip(subplots[0], axes):
            others = [a for a in axes if a != axis]
            numeric = _numeric(ok, axis)
            order = (
                sorted(ok[axis].dropna().unique(), key=lambda v: (isinstance(v, str), v))
                if numeric
                else list(dict.fromkeys(ok[axis].dropna()))
            )
            pos = {v: i for i, v in enumerate(order)}
            groups = ok.groupby(others, dropna=False) if others else [((), ok)]
            for name, g in groups:
                g = g.dropna(subset=[axis])
                if g.empty:
                    continue
                x = g[axis].astype(float).to_numpy() if numeric else g[axis].map(pos).to_numpy()
                idx = np.argsort(x)
                label = ", ".join(
                    f"{o}={v}" for o, v in zip(others, name if isinstance(name, tuple) else (name,))
                )
                ax.plot(x[idx], g[metric].to_numpy()[idx], "o-", ms=4, label=label or None)
            if not numeric:
                ax.set_xticks(range(len(order)), [str(v) for v in order], rotation=20)
            ax.set_xlabel(axis)
            ax.set_ylabel(metric)
            ax.grid(True, lw=0.3)
            if others and len(groups) <= 12:
                ax.legend(fontsize=7)
        fig.suptitle(f"{study.name}: {metric}")
        fig.tight_layout()
        path = folder / f"{metric}.png"
        _atomic(path, lambda p, fig=fig: fig.savefig(p, dpi=90, format="png"))
        plt.close(fig)
        out.append((metric, f"plots/{path.name}"))
    return out


def pareto_mask(points: np.ndarray, maximize: tuple[bool, ...]) -> np.ndarray:
    """Rows of ``points`` that no other row dominates (better or equal everywhere, better
    somewhere)."""
    p = np.where(np.array(maximize), -points, points)  # minimise everything
    keep = np.ones(len(p), bool)
    for i in range(len(p)):
        dominated = np.all(p <= p[i], axis=1) & np.any(p < p[i], axis=1)
        keep[i] = not dominated.any()
    return keep


def _feasible(study, df):
    ok = df["status"] == "ok"
    for c in study.constraints:
        if c.metric in df.columns:
            ok &= df[c.metric].map(lambda v, c=c: c.violation(v) <= 0)
        else:
            ok &= False
    return ok


def _save(fig, ax, title: str, path: Path) -> str:
    """Grid, legend and title; the PNG written atomically; its path relative to the report."""
    ax.grid(True, lw=0.3)
    ax.legend(fontsize=8)
    fig.suptitle(title)
    fig.tight_layout()
    _atomic(path, lambda p, fig=fig: fig.savefig(p, dpi=90, format="png"))
    plt.close(fig)
    return f"plots/{path.name}"


def _optuna_plots(study, df, folder: Path) -> list[tuple[str, str]]:
    out = []
    obj = study.objectives[0]
    if "trial" not in df.columns or obj.metric not in df.columns:
        return out
    d = df.sort_values("trial")
    feas = _feasible(study, d)
    fig, ax = plt.subplots(figsize=(7, 4))
    y = d[obj.metric].astype(float)
    ax.plot(d["trial"], y, "o", color="0.6", ms=4, label="infeasible or failed")
    ax.plot(d["trial"][feas], y[feas], "o", color="C0", ms=5, label="feasible")
    best = y.where(feas)
    best = best.cummax() if obj.direction == "maximize" else best.cummin()
    ax.step(d["trial"], best, where="post", color="C1", label="best feasible so far")
    ax.set_xlabel("trial")
    ax.set_ylabel(obj.metric)
    out.append(
        (
            "optimisation history",
            _save(
                fig,
                ax,
                f"{study.name}: optimisation history ({obj.direction})",
                folder / "optuna_history.png",
            ),
        )
    )
    pair = [o.metric for o in study.objectives][:2]
    directions = [o.direction == "maximize" for o in study.objectives][:2]
    if len(pair) < 2:  # one objective: its trade-off against the tail's mass
        pair, directions = ["mass_g", obj.metric], [False, obj.direction == "maximize"]
    if all(c in d.columns for c in pair):
        f = d[feas].dropna(subset=pair)
        fig, ax = plt.subplots(figsize=(6.5, 4.5))
        ax.plot(d[pair[0]], d[pair[1]], "o", color="0.75", ms=4, label="all trials")
        if not f.empty:
            pts = f[pair].astype(float).to_numpy()
            front = pareto_mask(pts, tuple(directions))
            ax.plot(pts[:, 0], pts[:, 1], "o", color="C0", ms=5, label="feasible")
            fp = pts[front][np.argsort(pts[front][:, 0])]
            ax.plot(fp[:, 0], fp[:, 1], "s-", color="C3", ms=6, label="Pareto front")
            base = f[f["label"] == "base"]
            if not base.empty:
                ax.plot(base[pair[0]], base[pair[1]], "*", color="k", ms=12, label="base")
        ax.set_xlabel(f"{pair[0]} ({'max' if directions[0] else 'min'})")
        ax.set_ylabel(f"{pair[1]} ({'max' if directions[1] else 'min'})")
        out.append(
            (
                "Pareto front",
                _save(fig, ax, f"{study.name}: Pareto front", folder / "pareto_front.png"),
            )
        )
    return out


def _spearman(x: np.ndarray, y: np.ndarray) -> float:
    from scipy.stats import spearmanr

    if len(x) < 3 or np.ptp(x) == 0 or np.ptp(y) == 0:
        return float("nan")
    return float(spearmanr(x, y).statistic)


def expectations(study, df) -> list[dict[str, Any]]:
    """Each expected trend with the rank correlation the results show and whether its sign
    agrees."""
    ok = df[df["status"] == "ok"]
    out = []
    for e in study.expect:
        if e.metric not in ok.columns or e.versus not in ok.columns:
            out.append({"expectation": e, "rho": float("nan"), "holds": None, "n": 0})
            continue
        sub = ok[[e.metric, e.versus]].dropna()
        if not _numeric(sub, e.versus):
            out.append({"expectation": e, "rho": float("nan"), "holds": None, "n": len(sub)})
            continue
        others = (
            [a for a in study.axes if a != e.versus and a in ok.columns]
            if e.versus in study.axes
            else []
        )
        if (
            others
        ):  # a trend along one axis holds at every setting of the others (e.g. per material)
            rhos = [
                _spearman(
                    g[e.versus].astype(float).to_numpy(), g[e.metric].astype(float).to_numpy()
                )
                for _, g in ok.dropna(subset=[e.metric, e.versus]).groupby(others, dropna=False)
            ]
            rhos = [r for r in rhos if not math.isnan(r)]
            rho = min(rhos, key=lambda r: r * e.sign) if rhos else float("nan")
        else:
            rho = _spearman(
                sub[e.versus].astype(float).to_numpy(), sub[e.metric].astype(float).to_numpy()
            )
        holds = None if math.isnan(rho) else bool(rho * e.sign > 0.5)
        out.append(
            {"expectation": e, "rho": rho, "holds": holds, "n": len(sub), "per_group": bool(others)}
        )
    return out


def _html(study, df, images: list[tuple[str, str]], trends: list[dict[str, Any]]) -> str:
    esc = html.escape
    counts = df["status"].value_counts().to_dict()
    parts = [
        f"<!doctype html><html><head><meta charset='utf-8'><title>{esc(study.name)}: design "
        "study</title>",
        "<style>body{font-family:sans-serif;max-width:1200px;margin:auto}table{border-collapse:collapse;"
        "font-size:12px}td,th{border:1px solid #ccc;padding:2px "
        "6px}td.bad{color:#b00}img{max-width:100%}"
        "</style></head><body>",
        f"<h1>Design study {esc(study.name)}</h1>",
        f"<p>{esc(study.kind)} study of <code>{esc(str(study.base_path))}</code>: {len(df)} "
        "variants; " + ", ".join(f"{esc(str(k))}: {v}" for k, v in counts.items()) + ".</p>",
    ]
    if trends:
        parts.append(
            "<h2>Trends the sources report, against the "
            "model</h2><table><tr><th>metric</th><th>expected"
            "</th><th>versus</th><th>rank "
            "correlation</th><th>variants</th><th>agrees</th><th>source</th>"
            "</tr>"
        )
        for t in trends:
            e = t["expectation"]
            verdict = {True: "yes", False: "no", None: "not measurable"}[t["holds"]]
            parts.append(
                f"<tr><td>{esc(e.metric)}</td><td>{'rises' if e.sign > 0 else 'falls'}</td>"
                f"<td>{esc(e.versus)}</td><td>{t['rho']:.2f}"
                f"{' (weakest over the other axes)' if t.get('per_group') else ''}"
                f"</td><td>{t['n']}</td>"
                f"<td class='{'' if t['holds'] else 'bad'}'>{verdict}</td>"
                f"<td>{esc(e.source)}</td></tr>"
            )
        parts.append("</table>")
    shown = [
        c for c in df.columns if not c.startswith("seconds_") and c != "checks_json"
    ]  # the table has them
    parts.append(
        "<h2>Results</h2><table><tr>" + "".join(f"<th>{esc(c)}</th>" for c in shown) + "</tr>"
    )
    for _, r in df.iterrows():
        cells = []
        for c in shown:
            v = r[c]
            text = (
                f"{v:.4g}"
                if isinstance(v, float) and not math.isnan(v)
                else ("" if v is None or (isinstance(v, float) and math.isnan(v)) else str(v))
            )
            bad = " class='bad'" if c == "status" and v != "ok" else ""
            cells.append(f"<td{bad}>{esc(text)}</td>")
        parts.append("<tr>" + "".join(cells) + "</tr>")
    parts.append("</table>")
    for title, src in images:
        parts.append(f"<h3>{esc(title)}</h3><img src='{esc(src)}' alt='{esc(title)}'>")
    parts.append("</body></html>")
    return "\n".join(parts)


__all__ = ["toml_text", "write_outputs", "expectations", "pareto_mask"]
