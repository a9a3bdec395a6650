"""What the studies' scripts share: read a record named SETTING:FREQUENCY, walk the
paper's grid in the coverage studies' order (``device.grid_case``), run jobs on local processes, write rows of
results to a CSV file and print them (and the run's entry into the folder's
manifest.json: ``bayes_inerter.study.manifest``), name the commit a run loaded, the
adaptive samplers they compare by name, and the model a stored chain sampled."""

import csv
import subprocess
import sys
from pathlib import Path

from bayes_inerter.device import setting_and_frequency
from bayes_inerter.executor import make_executor
from bayes_inerter.inference.sampling.adaptation import NAMED
from bayes_inerter.inference.sampling.checkpoint import stored_identity
from bayes_inerter.inference.sampling.coordinates import default_coordinates
from bayes_inerter.study.manifest import script_configuration, write_manifest

#: The paper's drive frequencies, Hz.
FREQUENCIES = (0.5, 1.0, 1.5)

#: The adaptive samplers compared side by side, by name (``adaptation.NAMED``).
ADAPTATIONS = NAMED


def record_arg(item: str) -> tuple[str, float]:
    """(setting, frequency in Hz) from a ``--record`` value SETTING:FREQUENCY ("A3:1");
    anything else ends the script with a one-line error."""
    try:
        return setting_and_frequency(item)
    except ValueError as exc:
        sys.exit(f"error: --record: {exc}")


def likelihood_changes(text: str) -> dict:
    """``likelihood.settings_changes``: ``--likelihood name=value,...`` as changes of
    ``LikelihoodSettings``."""
    from bayes_inerter.inference.posterior.likelihood import settings_changes

    return settings_changes(text)


def sbc_design_records(seed: int, replicates):
    """(replicate k, its frequency, its one record, b's truth) for each k of
    ``replicates``: the single-record calibration's devices of design seed ``seed``
    (``study_calibration.replicate_device``, the motion-in likelihood), replicate k at
    ``FREQUENCIES[k % 3]`` as the calibration fits it. (Imported here: the other
    scripts that share this module need not load the study, about 0.5 s.)"""
    from bayes_inerter.inference.posterior.likelihood import LikelihoodSettings
    from bayes_inerter.study.study_calibration import StudyCalibration, replicate_device

    cs = StudyCalibration(seed=seed, single=True, frequencies=FREQUENCIES, steps=None,
                          likelihood=LikelihoodSettings(residual="motion"))
    for k in replicates:
        dev = replicate_device(cs, k)
        yield k, cs.frequencies[k % len(cs.frequencies)], dev.records[0], dev.truth["b"]


def sampled_model(model, checkpoint):
    """(``model`` with the likelihood's reference point that the chain in ``checkpoint``
    was sampled with, where it took one; the coordinates the chain walked in): what a
    probe needs to evaluate the posterior a stored chain sampled. The sampler falls back
    from the impedance coordinates where the start lies outside their domain, so they are
    read from the checkpoint's identity, not assumed."""
    stored = stored_identity(checkpoint) or {}
    if stored.get("reference") is not None:
        model = model.with_reference(stored["reference"])
    return model, default_coordinates(model, (stored.get("coordinates") or {}).get("kind", "impedance"))


def git_commit(folder) -> str:
    """The short commit of the checkout ``folder`` lies in ("" outside a clone): read
    once when a run starts, as HEAD may move while it runs."""
    got = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=folder, capture_output=True, text=True)
    return got.stdout.strip() if got.returncode == 0 else ""


def map_rows(func, jobs: list, processes: int) -> list[dict]:
    """``func`` over ``jobs`` on ``processes`` local processes (at least one), in order;
    a ValueError (bad input, such as an unknown setting) ends the script with a
    one-line error."""
    try:
        with make_executor(max(1, processes)) as executor:
            return executor.map(func, jobs)
    except ValueError as exc:
        sys.exit(f"error: {exc}")


def write_table(path, rows: list[dict]) -> Path:
    """Write ``rows`` (dicts with the same keys) to the CSV file ``path``, its folder made
    if needed; return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(rows[0]))
        writer.writeheader()
        writer.writerows(rows)
    return path


def write_rows(path, rows: list[dict]) -> Path:
    """Write ``rows`` (dicts with the same keys) to the CSV file ``path`` (its folder made
    if needed, the run's entry added to its manifest.json), print each as
    ``key value, ...``, and return the path."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_manifest(path.parent, script_configuration())
    write_table(path, rows)
    for row in rows:
        print(", ".join(f"{k} {v}" for k, v in row.items()))
    return path


def read_rows(path) -> list[dict]:
    """The rows of the CSV file ``path`` as dicts of strings ([] where it does not exist)."""
    path = Path(path)
    if not path.exists():
        return []
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def append_row(path, row: dict, fields) -> None:
    """Append ``row`` to the CSV file ``path`` (its folder and header made where it is
    new, columns ``fields``) and print it as ``key value, ...``: a study that stops
    keeps every row it finished."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    write_manifest(path.parent, script_configuration())
    new = not path.exists()
    with open(path, "a", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=list(fields))
        if new:
            writer.writeheader()
        writer.writerow(row)
    print(", ".join(f"{k} {v}" for k, v in row.items()), flush=True)


def run_with_bar(run, total: int, desc: str, **bar):
    """``run(progress)`` with a progress bar of ``total`` steps on standard error
    (``progress(done, total)`` moves it; ``bar``: more tqdm options); a ValueError ends
    the script with a one-line error (exit 1)."""
    from tqdm import tqdm

    with tqdm(total=total, desc=desc, unit="replicate", file=sys.stderr, **bar) as shown:
        def progress(done, _total):
            shown.update(done - shown.n)

        try:
            return run(progress)
        except ValueError as exc:
            shown.close()
            sys.exit(f"error: {exc}")


def append_missing(path, key: str, items, make) -> None:
    """For each of ``items`` whose ``key`` column is not yet in the CSV file ``path``,
    ``make(item)``'s row appended (:func:`append_row`): a probe stopped part-way goes on
    where it stopped when run again."""
    done = {int(r[key]) for r in read_rows(path)}
    for item in items:
        if item not in done:
            row = make(item)
            append_row(path, row, list(row))
