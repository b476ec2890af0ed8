"""A run folder as a rosbag2 (MCAP): ``dualarm-qp bag RUN_DIR``.

The run's ``config.yaml`` rebuilds its task (the object's pose and ``D(t)`` are
computed from it), ``trajectory.csv`` gives the samples and ``summary.json`` the last
message. The bag (a folder: ``metadata.yaml`` and one ``.mcap`` file) is written into a
temporary folder beside its place and renamed into place when whole: an interrupted or
failed write leaves no bag, and an earlier bag of the same name stays until the new one
replaces it.
"""

from __future__ import annotations

import math
import os
import shutil
import tempfile
from collections import Counter
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from .._signals import SignalHold
from ..errors import DualArmError, InvalidInputError
from .messages import CdrMessages, Message
from .stream import Sample, StreamNames, samples_from_columns
from .topics import TOPICS

#: The bag's folder in a run folder (the default of ``dualarm-qp bag``).
BAG_FOLDER = "bag"


@dataclass
class RunStream:
    """A finished run, ready to be streamed: its task, names, samples and summary.

    Attributes
    ----------
    run : Path
        The run folder.
    messages : CdrMessages
        The messages of its samples.
    samples : list of Sample
        One per row of ``trajectory.csv``.
    summary : dict
        Its ``summary.json``.
    """

    run: Path
    messages: CdrMessages
    samples: list[Sample]
    summary: dict[str, Any]

    @classmethod
    def read(cls, run_dir: str | Path) -> RunStream:
        """Read a run folder (``summary.json``, ``trajectory.csv``, ``config.yaml``).

        Raises
        ------
        InvalidInputError
            Not a run folder, its task cannot be rebuilt, or a time is negative.
        """
        from ..experiments.animate import read_run_summary, run_config
        from ..experiments.config import load_config
        from ..experiments.figures.rundata import RunData
        from ..experiments.setup import build_experiment

        run = Path(run_dir)
        if not run.is_dir():
            raise InvalidInputError(f"{run}: not a folder (RUN_DIR is the output folder of a "
                                    "run or a drive)")
        summary = read_run_summary(run)
        config = run_config(run, summary)
        try:
            cfg = load_config(config)
            exp = build_experiment(cfg, str(config))
            names = StreamNames.of(exp.task, cfg.cell.leader.joints, cfg.cell.follower.joints,
                                   path=str(config))
        except DualArmError as err:
            raise InvalidInputError(f"cannot rebuild the task of {run}: {err}") from None
        csv_path = run / "trajectory.csv"
        if not csv_path.is_file():
            raise InvalidInputError(f"{csv_path}: not found (a run folder holds it)")
        data = RunData.read(csv_path)
        samples = samples_from_columns(data.columns, exp.task.leader.n, exp.task.follower.n)
        bad = next((s.t for s in samples if not (math.isfinite(s.t) and s.t >= 0.0)), None)
        if bad is not None:
            raise InvalidInputError(f"{csv_path}: a time of {bad!r} s; a bag's times are "
                                    "finite and not negative")
        return cls(run, CdrMessages(exp.task, names), samples, summary)

    def stream(self) -> Iterator[Message]:
        """Yield every message in time order: each sample's, then the summary."""
        for s in self.samples:
            yield from self.messages.sample(s)
        last = self.samples[-1].stamp_ns if self.samples else 0
        yield self.messages.summary(self.summary, last)


def write_bag_folder(path: Path, stream: RunStream) -> Counter[str]:
    """Write ``stream`` as a rosbag2 in MCAP into the new folder ``path``.

    Returns
    -------
    Counter
        The messages written per topic.
    """
    from rosbags.rosbag2 import StoragePlugin, Writer

    store = stream.messages.store
    counts: Counter[str] = Counter()
    with Writer(path, version=9, storage_plugin=StoragePlugin.MCAP) as writer:
        conns = {topic: writer.add_connection(topic, msgtype, typestore=store)
                 for topic, msgtype in TOPICS.items()}
        for msg in stream.stream():
            writer.write(conns[msg.topic], msg.stamp_ns, msg.data)
            counts[msg.topic] += 1
    return counts


def write_bag(run_dir: str | Path, out: str | Path | None = None, *, force: bool = False
              ) -> tuple[Path, Counter[str]]:
    """Write the bag of a finished run (see the module).

    Parameters
    ----------
    run_dir : path
        A folder written by ``dualarm-qp run`` or ``drive``.
    out : path, optional
        The bag's folder; default ``run_dir/bag``.
    force : bool
        Replace an existing bag there (only a folder that holds a ``metadata.yaml``).

    Returns
    -------
    path : Path
        The bag's folder.
    counts : Counter
        The messages written per topic.

    Raises
    ------
    InvalidInputError
        Not a run folder, or ``out`` exists (and is not a bag to replace with ``force``).
    """
    stream = RunStream.read(run_dir)
    target = Path(out) if out is not None else Path(run_dir) / BAG_FOLDER
    if target.exists() or target.is_symlink():
        if not (force and target.is_dir() and (target / "metadata.yaml").is_file()):
            raise InvalidInputError(f"{target} exists; choose another --out, or pass --force "
                                    "to replace the bag there")
    target.parent.mkdir(parents=True, exist_ok=True)
    work = Path(tempfile.mkdtemp(prefix=f".{target.name}.", dir=target.parent))
    try:
        fresh = work / target.name  # the .mcap file takes the folder's name
        counts = write_bag_folder(fresh, stream)
        with SignalHold():  # the old bag goes only once the new one is in place
            old = None
            if target.exists():
                old = work / "replaced"
                os.replace(target, old)
            os.replace(fresh, target)
    finally:
        with SignalHold():
            shutil.rmtree(work, ignore_errors=True)
    return target, counts


__all__ = ["BAG_FOLDER", "RunStream", "write_bag", "write_bag_folder"]
