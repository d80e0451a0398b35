"""`bvsr sweep`: design studies on Dask, with Optuna for searches.

A study (:mod:`bvsr_cad.parameters.study`) becomes variants; each variant runs as
one Dask task (:func:`evaluate`), which starts a fresh Python process for it
(``python -m bvsr_cad.studies.sweep -``: the variant's mapping in, its row out, pickled).
The process computes only the metric groups the study asks for
(:mod:`bvsr_cad.analysis.metrics`) and, with ``checks = true``, exports the
variant and runs every check. The child isolates what a variant can do wrong:
an impossible tail is a row with the loader's reason (``infeasible``), an
exception a row with it (``error``), a variant over the study's time limit is
killed and recorded as ``timeout``, and a child dies with the Dask worker that
started it (PR_SET_PDEATHSIG), so a killed worker leaves nothing running; Dask
then reruns its task on another worker.

The engine is ``dask.distributed``: a ``LocalCluster`` of ``--workers`` processes
(one thread each) or, with ``--scheduler tcp://host:8786``, an existing cluster
whose workers have this package installed (the task carries the whole variant,
so workers need no shared folder unless ``checks`` keeps exports).

Results: every finished row is appended to ``results.jsonl`` in the study's
folder as it arrives, so an interrupted study resumes (a rerun skips the
variants whose key, a hash of the variant's whole parameter mapping, is there);
at the end ``results.parquet`` and ``results.csv`` hold one row per variant and
``report.html`` the plots. An Optuna study asks and tells from this process and
keeps its trials in Optuna's journal file (``optuna.journal``), a storage many
processes may share (not SQLite); its trials' rows resume the same way.
"""

from __future__ import annotations

import json
import logging
import math
import os
import pickle
import subprocess
import sys
import tempfile
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..analysis.metrics import METRICS, Conditions, group_of
from ..errors import BadInput
from ..extras import require
from ..parameters.study import Study, StudyError, Variant, get_path
from ..pipeline.processes.worker import child_env

#: Metrics of the ``checks`` group (a full export and every check of it).
CHECK_METRICS = {
    "checks_total": "number of checks with a verdict",
    "checks_failed": "number of failed checks",
    "checks_passed_ok": "every check passed",
    "failed_checks": "names of the failed checks (first 20)",
    "checks_json": "every check's verdict: a JSON object {check name: passed}",
}
STATUSES = ("ok", "infeasible", "timeout", "error")
JOURNAL = "results.jsonl"


class SweepError(RuntimeError, BadInput):
    """The study could not run (no scheduler at the address, an unwritable output folder)."""


@dataclass(frozen=True)
class Plan:
    """What every variant computes: model metric groups, and whether it is exported and checked."""

    groups: tuple[str, ...]
    checks: bool


def plan(study: Study) -> Plan:
    """The groups a study needs; an unknown metric anywhere (metrics, objectives, constraints,
    expectations) is a :class:`StudyError` naming it."""
    problems, groups, checks = [], [], study.checks
    allowed = ", ".join([*METRICS, "checks"])

    def need(name: str, where: str) -> None:
        nonlocal checks
        if name in METRICS:
            groups.append(name)
        elif name == "checks" or name in CHECK_METRICS:
            checks = True
        elif group_of(name):
            groups.append(group_of(name))
        elif not (name in study.axes or name.startswith("fitted_")):
            known = sorted(m for g in METRICS.values() for m in g)
            problems.append(
                f"{where} {name!r}: not a metric; groups: {allowed}; metrics: {', '.join(known)}, "
                f"{', '.join(CHECK_METRICS)}"
            )

    for m in study.metrics:
        need(m, "metrics")
    for o in study.objectives:
        need(o.metric, "optuna.objectives")
    for c in study.constraints:
        need(c.metric, "optuna.constraints")
    for e in study.expect:
        need(e.metric, "expect")
        need(e.versus, "expect")
    if problems:
        raise StudyError(study.path, problems)
    return Plan(tuple(dict.fromkeys(groups)), checks)


# -- one variant
# --------------------------------------------------------------------------------------


def payload(
    study: Study, variant: Variant, pl: Plan, export_root: Path | None = None
) -> dict[str, Any]:
    """Everything a worker needs for one variant (no file of this machine is read there)."""
    data = json.loads(json.dumps(variant.data, default=str))
    data["name"] = (
        f"{study.name}_{variant.key[:8]}"  # its own tail: the base's measurements are not its own
    )
    return {
        "key": variant.key,
        "label": variant.label,
        "study": study.name,
        "data": data,
        "groups": list(pl.groups),
        "checks": pl.checks,
        "conditions": dict(study.conditions),
        "time_limit_s": study.time_limit_s,
        "axes": {
            k: _plain(get_path(variant.data, k)) for k in study.axes
        },  # None: the schema's default
        "export_dir": None if export_root is None else str(export_root / variant.key),
    }


def _row(task: dict[str, Any], status: str, reason: str, **extra: Any) -> dict[str, Any]:
    """A result row: the variant's key, label and axis values, its status and why."""
    return {
        "key": task["key"],
        "label": task["label"],
        **task["axes"],
        "status": status,
        "reason": reason,
        **extra,
    }


def _plain(v: Any) -> Any:
    return v if isinstance(v, (str, int, float, bool)) or v is None else str(v)


def infeasible_reason(variant: Variant) -> str:
    """Why the variant's parameters describe no buildable tail (the loader's problems), or ""."""
    from ..parameters.load import ParamError, spec_from_dict

    try:
        spec_from_dict(variant.data, f"variant {variant.label}")
    except ParamError as exc:
        return _problems_text(exc.problems)
    return ""


def _problems_text(problems: list[str], first: int = 5) -> str:
    more = f"; and {len(problems) - first} more" if len(problems) > first else ""
    return "; ".join(problems[:first]) + more


def evaluate(task: dict[str, Any]) -> dict[str, Any]:
    """The Dask task: run one variant in a fresh process, within the study's time limit."""
    import socket

    t0 = time.perf_counter()
    row = _row(task, "error", "", worker=f"{socket.gethostname()}:{os.getpid()}")
    # The study's name on the command line: `ps` shows which study a variant's process belongs to.
    proc = subprocess.Popen(
        [sys.executable, "-m", "bvsr_cad.studies.sweep", "-", task["study"]],
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        env=child_env(),
    )
    try:
        out, err = proc.communicate(json.dumps(task).encode(), timeout=task["time_limit_s"])
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        row.update(
            status="timeout",
            reason=f"ran over the study's time_limit_s = {task['time_limit_s']:g} s",
        )
    except BaseException:
        proc.kill()
        proc.wait()
        raise
    else:
        try:
            kind, result, _cpu_s = pickle.loads(out)  # worker.serve's answer
        except Exception:  # noqa: BLE001 - the child died without a result
            tail = err.decode("utf-8", "replace").strip().splitlines()[-3:]
            row["reason"] = (
                f"the variant's process ended with code {proc.returncode}: " + " | ".join(tail)
            )
        else:
            if kind == "ok":
                row.update(result)
            else:
                row["reason"] = f"{type(result).__name__}: {result}"
    row["seconds"] = time.perf_counter() - t0
    return row


def _variant_here(task: dict[str, Any]) -> dict[str, Any]:
    """The child's work: load the variant, compute its metrics (and export and check it)."""
    from ..analysis.metrics import model_metrics
    from ..parameters.load import ParamError, spec_from_dict

    _clean_dead_workdirs()
    try:
        spec = spec_from_dict(task["data"], f"variant {task['label']}")
    except ParamError as exc:
        return {"status": "infeasible", "reason": _problems_text(exc.problems)}
    row: dict[str, Any] = {"status": "ok", "reason": ""}
    if task["groups"]:
        row.update(model_metrics(spec, task["groups"], Conditions(**task["conditions"])))
    if task["checks"]:
        row.update(_export_and_check(task))
    return row


WORKDIR_PREFIX = "bvsr-variant-"


def _export_and_check(task: dict[str, Any]) -> dict[str, Any]:
    from ..exporters.study_report import toml_text
    from ..pipeline.processes.checks_process import run_checks
    from ..pipeline.stages import build_export

    with tempfile.TemporaryDirectory(prefix=f"{WORKDIR_PREFIX}{os.getpid()}-") as tmp:
        params = Path(tmp) / f"{task['data']['name']}.toml"
        params.write_text(toml_text(task["data"]), encoding="utf-8")
        out = Path(task["export_dir"]) if task.get("export_dir") else Path(tmp) / "export"
        t = time.perf_counter()
        build_export(params, out)
        results = run_checks(out, parallel=False)
    failed = [r.name for r in results if r.passed is False]
    verdicts = [r for r in results if r.passed is not None]
    return {
        "checks_total": len(verdicts),
        "checks_failed": len(failed),
        "checks_passed_ok": not failed,
        "failed_checks": "; ".join(failed[:20]),
        "checks_json": json.dumps({r.name: r.passed for r in verdicts}, sort_keys=True),
        "seconds_checks": time.perf_counter() - t,
    }


def _clean_dead_workdirs() -> None:
    """Remove work folders of variant processes that no longer run (killed with their worker)."""
    import shutil

    root = Path(tempfile.gettempdir())
    for folder in root.glob(f"{WORKDIR_PREFIX}*"):
        try:
            pid = int(folder.name[len(WORKDIR_PREFIX) :].split("-")[0])
        except ValueError:
            continue
        if pid != os.getpid() and not Path(f"/proc/{pid}").exists():
            shutil.rmtree(folder, ignore_errors=True)


# -- results
# ------------------------------------------------------------------------------------------


def read_journal(path: Path) -> dict[str, dict[str, Any]]:
    """Rows by key (the last one wins); a torn last line (a killed run) is skipped."""
    rows: dict[str, dict[str, Any]] = {}
    if path.exists():
        for line in path.read_text(encoding="utf-8").splitlines():
            try:
                row = json.loads(line)
            except json.JSONDecodeError:
                continue
            rows[row["key"]] = row
    return rows


def _append(path: Path, row: dict[str, Any]) -> None:
    with path.open("a", encoding="utf-8") as fh:
        fh.write(json.dumps(row, default=_plain) + "\n")
        fh.flush()
        os.fsync(fh.fileno())


@dataclass
class StudyResult:
    study: Study
    out_dir: Path
    rows: list[dict[str, Any]]
    reused: int
    computed: int
    seconds: float
    workers: int
    files: dict[str, str]
    best: dict[str, Any] | None = None

    def as_json(self) -> dict[str, Any]:
        counts = {s: sum(r["status"] == s for r in self.rows) for s in STATUSES}
        return {
            "study": self.study.name,
            "kind": self.study.kind,
            "out_dir": str(self.out_dir),
            "variants": len(self.rows),
            "reused": self.reused,
            "computed": self.computed,
            "status": counts,
            "workers": self.workers,
            "seconds": round(self.seconds, 2),
            "files": self.files,
            "best": self.best,
            "rows": self.rows,
        }


# -- the engine
# ---------------------------------------------------------------------------------------


class _Cluster:
    """A Dask client on a new LocalCluster or an existing scheduler; closing it stops what it
    started."""

    def __init__(self, scheduler: str | None, workers: int | None):
        from distributed import Client, LocalCluster

        self.cluster = None
        try:
            if scheduler:
                self.client = Client(scheduler, timeout="10s")
            else:
                n = workers or max(1, (os.cpu_count() or 1))
                self.cluster = LocalCluster(
                    n_workers=n,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                    silence_logs=logging.CRITICAL,
                )
                self.client = Client(self.cluster)
        except (OSError, TimeoutError) as exc:
            raise SweepError(f"no Dask scheduler at {scheduler!r}: {exc}") from None

    @property
    def n_workers(self) -> int:
        return max(1, len(self.client.scheduler_info(n_workers=-1).get("workers", {})))

    def close(self) -> None:
        self.client.close()
        if self.cluster is not None:
            self.cluster.close()


def run_study(
    study: Study,
    out_dir: str | Path | None = None,
    scheduler: str | None = None,
    workers: int | None = None,
    progress: bool = True,
    keep_exports: bool = False,
    say: Callable[[str], None] | None = None,
) -> StudyResult:
    """Run every variant of ``study`` not already in its journal; write the table and the report.

    Raises:
        StudyError: a metric the study names does not exist.
        SweepError: the cluster cannot be reached.
        ExtraMissing: the ``studies`` extra (Dask, Optuna, pandas, ...) is not installed.
    """
    require("studies", "bvsr sweep")
    from ..exporters.study_report import write_outputs

    say = say or (lambda _m: None)
    t0 = time.perf_counter()
    pl = plan(study)
    _require_buildable_base(study)
    out = _study_folder(study, out_dir)
    journal = out / JOURNAL
    # What a rerun keeps: results and impossible tails. A timeout or an error is tried again (with a
    # longer time_limit_s, or after a fix), so a rerun finishes what an earlier one could not.
    done = {
        k: r for k, r in read_journal(journal).items() if r.get("status") in ("ok", "infeasible")
    }
    export_root = (out / "variants") if keep_exports else None
    previous = _terminate_as_interrupt()
    cluster = None
    try:
        cluster = _Cluster(scheduler, workers)
        n_workers = cluster.n_workers
        say(
            f"study {study.name}: {study.kind}, groups {', '.join(pl.groups) or '-'}"
            f"{', export + checks' if pl.checks else ''}; {n_workers} Dask worker(s)"
            f"{' at ' + scheduler if scheduler else ''}"
        )
        if study.kind == "optuna":
            rows, reused, best = _optuna(
                study, pl, cluster, journal, done, export_root, progress, n_workers
            )
        else:
            rows, reused = _listed_variants(
                study, pl, cluster, journal, done, export_root, progress, say
            )
            best = None
    finally:
        if cluster is not None:
            cluster.close()  # its workers stop, and each variant's process dies with its worker
        _restore(previous)
    files = write_outputs(study, rows, out)
    return StudyResult(
        study,
        out,
        rows,
        reused,
        len(rows) - reused,
        time.perf_counter() - t0,
        n_workers,
        files,
        best,
    )


def _require_buildable_base(study: Study) -> None:
    """Raise StudyError when the study's base with its [set] is not a buildable tail."""
    base_problem = infeasible_reason(study.variant({}, "base"))
    if base_problem:
        raise StudyError(
            study.path,
            [f"base = {str(study.base_path)!r} with [set] is not a buildable tail: {base_problem}"],
        )


def _study_folder(study: Study, out_dir: str | Path | None) -> Path:
    """The study's output folder, created (default exports/studies/<name>); SweepError if it
    cannot be."""
    out = Path(out_dir) if out_dir is not None else Path("exports") / "studies" / study.name
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise SweepError(f"cannot use {str(out)!r} as the study folder: {exc}") from None
    return out


def _listed_variants(
    study: Study,
    pl: Plan,
    cluster: _Cluster,
    journal: Path,
    done: dict[str, dict[str, Any]],
    export_root: Path | None,
    progress: bool,
    say: Callable[[str], None],
) -> tuple[list[dict[str, Any]], int]:
    """A grid or random study: every listed variant not yet in ``done`` runs on the cluster, an
    infeasible one is recorded without a worker. Its rows in the study's order and how many were
    reused from the journal."""
    variants = study.variants()
    todo = [v for v in variants if v.key not in done]
    reused = len(variants) - len(todo)
    tasks = []
    for v in todo:  # an impossible tail is found here, at once, without a worker
        task = payload(study, v, pl, export_root)
        reason = infeasible_reason(v)
        if reason:
            row = _row(task, "infeasible", reason)
            _append(journal, row)
            done[v.key] = row
        else:
            tasks.append(task)
    say(
        f"{len(variants)} variants: {reused} already in {journal.name}, "
        f"{len(todo) - len(tasks)} infeasible "
        f"(recorded with the reason), {len(tasks)} to run"
    )
    new = _run_many(cluster, tasks, journal, progress, study.name)
    done.update(new)
    return [done[v.key] for v in variants], reused


def _terminate_as_interrupt():
    """SIGTERM stops a study like Ctrl-C (the cluster is closed on the way out); the old handler."""
    import signal
    import threading

    if threading.current_thread() is not threading.main_thread():
        return None

    def stop(_signum, _frame):
        raise KeyboardInterrupt

    return signal.signal(signal.SIGTERM, stop)


def _restore(previous) -> None:
    import signal

    if previous is not None:
        signal.signal(signal.SIGTERM, previous)


def _bar(total: int, enabled: bool, name: str):
    from tqdm import tqdm

    return tqdm(
        total=total,
        file=sys.stderr,
        disable=not enabled,
        desc=name,
        unit="variant",
        dynamic_ncols=True,
    )


def _result(fut, task: dict[str, Any]) -> dict[str, Any]:
    try:
        return fut.result()
    except Exception as exc:  # noqa: BLE001 - a task that failed three times (e.g. killed workers)
        return _row(task, "error", f"the task failed: {type(exc).__name__}: {exc}")


def _first_done(futures) -> list:
    """The futures that finished, waiting in short slices so that Ctrl-C and SIGTERM are seen at
    once (a plain blocking wait holds the main thread inside Dask's event-loop call)."""
    from distributed import wait

    while True:
        try:
            return list(wait(list(futures), timeout=0.5, return_when="FIRST_COMPLETED").done)
        except TimeoutError:
            continue


def _run_many(
    cluster: _Cluster, tasks: list[dict[str, Any]], journal: Path, progress: bool, name: str
) -> dict[str, dict[str, Any]]:
    rows: dict[str, dict[str, Any]] = {}
    if not tasks:
        return rows
    futures = {
        cluster.client.submit(evaluate, t, key=f"bvsr-variant-{t['key']}", pure=False): t
        for t in tasks
    }
    with _bar(len(tasks), progress, name) as bar:
        while futures:
            for fut in _first_done(futures):
                task = futures.pop(fut)
                row = _result(fut, task)
                rows[task["key"]] = row
                _append(journal, row)
                bar.set_postfix_str(f"{task['label'][:40]}: {row['status']}")
                bar.update(1)
    return rows


def _optuna(
    study: Study,
    pl: Plan,
    cluster: _Cluster,
    journal: Path,
    done: dict[str, dict[str, Any]],
    export_root: Path | None,
    progress: bool,
    slots: int,
):
    """An Optuna study: trials are asked and run on the cluster, up to ``slots`` at a time, until
    ``study.trials`` have finished; a tail already in ``done`` answers its trial without running.
    Its rows, how many were reused and the best trial(s)."""
    from optuna.trial import TrialState

    ost = _optuna_study(study, journal)
    # Trials that count towards the study: those whose tail has a row (a trial interrupted before
    # its row was written does not count, and is asked again).
    finished = [
        t
        for t in ost.get_trials(deepcopy=False)
        if t.state in (TrialState.COMPLETE, TrialState.FAIL) and t.user_attrs.get("variant") in done
    ]
    rows = {t.user_attrs["variant"]: done[t.user_attrs["variant"]] for t in finished}
    reused = len(rows)
    in_flight: dict[Any, tuple[Any, Variant, dict]] = {}

    with _bar(study.trials, progress, study.name) as bar:
        bar.update(len(finished))
        count = len(finished)

        def finish(trial, v: Variant, row: dict[str, Any], new: bool) -> None:
            """Record a trial's row (appended to the journal when it is new) and tell Optuna."""
            nonlocal count, reused
            row = {**row, "trial": trial.number}
            if new:
                _append(journal, row)
                done[v.key] = rows[v.key] = row
            else:  # one row per tail: a tail asked again keeps its first trial's row
                reused += v.key not in rows
                rows.setdefault(v.key, row)
            _tell(study, ost, trial, row)
            count += 1
            bar.set_postfix_str(f"trial {trial.number}: {row['status']}")
            bar.update(1)

        while count + len(in_flight) < study.trials or in_flight:
            while len(in_flight) < slots and count + len(in_flight) < study.trials:
                trial = ost.ask()
                over = _suggest(study, trial)
                v = study.variant(over, "base" if trial.user_attrs.get("baseline") else None)
                trial.set_user_attr("variant", v.key)
                task = payload(study, v, pl, export_root)
                reason = "" if v.key in done else infeasible_reason(v)
                if v.key in done:
                    # the same tail ran before (an earlier trial or run): its row answers
                    finish(trial, v, done[v.key], new=False)
                elif reason:
                    finish(trial, v, _row(task, "infeasible", reason), new=True)
                else:
                    fut = cluster.client.submit(
                        evaluate, task, key=f"bvsr-trial-{trial.number}-{v.key}", pure=False
                    )
                    in_flight[fut] = (trial, v, task)
            for fut in _first_done(in_flight) if in_flight else ():
                trial, v, task = in_flight.pop(fut)
                finish(trial, v, _result(fut, task), new=True)
    return list(rows.values()), reused, _best(study, ost)


def _optuna_study(study: Study, journal: Path):
    """The study's Optuna study in its journal file next to ``journal``, created or loaded: the
    trials an interrupted run left running are failed, and a new study with ``baseline`` asks the
    base tail first."""
    import optuna
    from optuna.storages import JournalStorage
    from optuna.storages.journal import JournalFileBackend
    from optuna.trial import TrialState

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    storage = JournalStorage(JournalFileBackend(str(journal.parent / "optuna.journal")))

    # Feasibility reaches the sampler through each trial's set_constraint values.
    sampler = (
        optuna.samplers.RandomSampler if study.sampler == "random" else optuna.samplers.TPESampler
    )(seed=study.seed)
    ost = optuna.create_study(
        study_name=study.name,
        storage=storage,
        sampler=sampler,
        load_if_exists=True,
        directions=[o.direction for o in study.objectives],
    )
    for t in ost.get_trials(deepcopy=False, states=(TrialState.RUNNING,)):
        ost.tell(t.number, state=TrialState.FAIL)
    if study.baseline and not ost.get_trials(deepcopy=False):
        base = {d.key: get_path(study.base_data, d.key) for d in study.space}
        ost.enqueue_trial(
            {k: v for k, v in base.items() if v is not None}, user_attrs={"baseline": True}
        )
    return ost


def _suggest(study: Study, trial) -> dict[str, Any]:
    """The trial's value of each of the study's design variables (a choice or a float range)."""
    return {
        d.key: (
            trial.suggest_categorical(d.key, list(d.choices))
            if d.choices is not None
            else trial.suggest_float(d.key, d.low, d.high, step=d.step, log=d.log)
        )
        for d in study.space
    }


def _tell(study: Study, ost, trial, row: dict[str, Any]) -> None:
    """Tell Optuna a trial's outcome: its objectives and constraint violations when the tail ran
    and every objective is a finite number, else a failure with the row's status and reason."""
    from optuna.trial import TrialState

    values = [row.get(o.metric) for o in study.objectives]
    if row["status"] == "ok" and all(
        isinstance(x, (int, float)) and math.isfinite(x) for x in values
    ):
        violations = [c.violation(row.get(c.metric)) for c in study.constraints]
        for c, x in zip(study.constraints, violations):
            trial.set_constraint(c.metric, x)  # how the sampler learns feasibility
        trial.set_user_attr("constraints", violations)
        ost.tell(trial, values)
    else:
        trial.set_user_attr("failure", f"{row['status']}: {row.get('reason', '')}"[:500])
        ost.tell(trial, state=TrialState.FAIL)


def _best(study: Study, ost) -> dict[str, Any] | None:
    """The best feasible trial (one objective: the best value among completed trials whose every
    constraint holds) or the feasible Pareto front's trial numbers (several objectives)."""
    from optuna.trial import TrialState

    feasible = [
        t
        for t in ost.get_trials(deepcopy=False, states=(TrialState.COMPLETE,))
        if all(x <= 0 for x in t.user_attrs.get("constraints", []))
    ]
    if not feasible:
        return None
    if len(study.objectives) == 1:
        pick = max if study.objectives[0].direction == "maximize" else min
        t = pick(feasible, key=lambda tr: tr.values[0])
        return {
            "trial": t.number,
            "variant": t.user_attrs["variant"],
            "params": t.params,
            "value": t.values[0],
            "metric": study.objectives[0].metric,
        }
    from ..exporters.study_report import pareto_mask

    values = np.array([t.values for t in feasible])
    front = pareto_mask(values, tuple(o.direction == "maximize" for o in study.objectives))
    return {"pareto_trials": sorted(t.number for t, keep in zip(feasible, front) if keep)}


def _main() -> int:
    """``python -m bvsr_cad.studies.sweep -``: one variant (JSON on stdin), its row pickled onto
    stdout."""
    from ..pipeline.processes.worker import serve

    task = json.loads(sys.stdin.buffer.read())
    return serve("-", _variant_here, task)


if __name__ == "__main__":
    sys.exit(_main())
