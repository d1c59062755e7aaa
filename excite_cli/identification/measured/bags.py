"""ROS bags as labs record them, read with the ``rosbags`` library (no ROS installation): a ROS 1
``.bag``, or a ROS 2 bag (its folder, or its ``.db3`` SQLite3 or ``.mcap`` file). The
``sensor_msgs/JointState`` messages of one topic become a :class:`~excite_cli.identification.measured.files.Table`
with the columns ``time`` (the header stamp [s]; the recording time where the stamp is 0) and, per
joint, ``position/<joint>``, ``velocity/<joint>``, ``effort/<joint>`` (those the messages fill).

Joints are matched by name, so the order of ``name`` in the messages does not matter; messages that
do not carry every wanted joint (another publisher on the same topic, e.g. a gripper) are skipped.
"""

from __future__ import annotations

import warnings
from pathlib import Path
from typing import Sequence

import numpy as np
from rosbags.highlevel import AnyReader, AnyReaderError
from rosbags.typesys import Stores, get_typestore

from excite_cli.errors import ExciteError, ExciteWarning
from excite_cli.identification.measured.files import Table
from excite_cli.inputs import input_file

BAG_SUFFIXES = (".bag", ".db3", ".mcap")
FIELDS = ("position", "velocity", "effort")


def is_bag(path: Path) -> bool:
    """Whether ``path`` is a ROS bag: a ``.bag``, ``.db3`` or ``.mcap`` file, or a ROS 2 bag folder."""
    return path.suffix.lower() in BAG_SUFFIXES or (path.is_dir() and (path / "metadata.yaml").is_file())


def _bag_paths(path: Path) -> list[Path]:
    """What ``AnyReader`` opens: a ROS 1 file, or the folder of a ROS 2 bag."""
    if path.suffix.lower() in (".db3", ".mcap") and (path.parent / "metadata.yaml").is_file():
        return [path.parent]
    return [path]


#: Messages that each carry part of the active joints are one sample when their stamps differ by at most
#: this [s] (a driver that publishes an arm's joints in several JointState messages, stamped together).
MERGE_TOLERANCE_S = 0.001


def _rows(reader: AnyReader, connections: list, joints: Sequence[str]) -> tuple[list[np.ndarray], int]:
    """(1 + 3n,) rows [time, position, velocity, effort] of the samples carrying every joint (NaN where
    a message leaves a field empty), in recorded order (by stamp where parts were merged), and the
    number of messages left out: those
    that carry some of the joints and no message within :data:`MERGE_TOLERANCE_S` completes (those
    that carry none are another publisher's: a gripper's). Messages that together carry every joint
    once, stamped within the tolerance, are merged into one sample, joints by name."""
    rows, skipped, merged = [], 0, False
    wanted = set(joints)
    pending: list[tuple[float, dict[str, list[float]], int]] = []  # (stamp, joint → values, messages)
    for connection, recorded_ns, raw in reader.messages(connections=connections):
        message = reader.deserialize(raw, connection.msgtype)
        names = list(message.name)
        carried = wanted & set(names)
        if not carried:
            continue
        stamp = message.header.stamp.sec + 1e-9 * message.header.stamp.nanosec
        stamp = stamp if stamp > 0 else 1e-9 * recorded_ns
        values = {}
        for name in FIELDS:
            field = np.asarray(getattr(message, name), dtype=float)
            for j in carried:
                values.setdefault(j, []).append(field[names.index(j)] if field.size == len(names) else np.nan)
        if carried != wanted:  # part of a sample: merged with the parts stamped with it
            stale = [p for p in pending if p[0] < stamp - 10 * MERGE_TOLERANCE_S]
            skipped += sum(p[2] for p in stale)
            pending = [p for p in pending if p not in stale]
            match = next(
                (p for p in pending if abs(p[0] - stamp) <= MERGE_TOLERANCE_S and not carried & p[1].keys()), None
            )
            if match is None:
                pending.append((stamp, values, 1))
                continue
            pending.remove(match)
            values, count = {**match[1], **values}, match[2] + 1
            if values.keys() != wanted:
                pending.append((match[0], values, count))
                continue
            stamp, merged = match[0], True
        row = [stamp] + [values[j][f] for f in range(len(FIELDS)) for j in joints]
        rows.append(np.array(row))
    skipped += sum(p[2] for p in pending)
    if merged:  # merged parts complete out of recorded order; other stamps are left for the run's checks
        rows.sort(key=lambda r: r[0])
    return rows, skipped


def read_bag(path: Path, topic: str, joints: Sequence[str]) -> Table:
    """The JointState messages of ``topic`` in the bag at ``path`` (module docstring) as a Table.

    Args:
        topic: the ``sensor_msgs/JointState`` topic (``data.topic``).
        joints: (n,) the active joints' names, as in the URDF.

    Messages that carry some of the active joints but not all are merged, by joint name, with those
    stamped within :data:`MERGE_TOLERANCE_S` of them that carry the others (a driver publishing an
    arm in several messages); the parts no message completes are left out, counted in
    ``Table.dropped`` and named in an :class:`~excite_cli.errors.ExciteWarning` (messages that carry
    none of the joints are another publisher's, a gripper's, and are passed over).

    Raises:
        ExciteError: not a readable bag (a FIFO or device: :func:`~excite_cli.inputs.input_file`), no such topic or not
            JointState, no message with every joint.
    """
    if not path.is_dir():  # a ROS 1 file or a ROS 2 bag's .db3 / .mcap
        input_file(path, "data.runs", "ROS bag")
    try:
        with AnyReader(_bag_paths(path), default_typestore=get_typestore(Stores.LATEST)) as reader:
            connections = [c for c in reader.connections if c.topic == topic]
            if not connections:
                found = sorted({c.topic for c in reader.connections})
                raise ExciteError("data.topic", f"{path.name} has no topic {topic} (it has: {', '.join(found)})", topic)
            kinds = {c.msgtype for c in connections}
            if any(not k.endswith("JointState") for k in kinds):
                raise ExciteError(
                    "data.topic",
                    f"{topic} in {path.name} carries {', '.join(sorted(kinds))}",
                    topic,
                    "sensor_msgs/JointState messages",
                )
            rows, skipped = _rows(reader, connections, joints)
    except (AnyReaderError, OSError, KeyError, ValueError) as exc:
        raise ExciteError("data", f"cannot read {path.name} as a ROS bag: {' '.join(str(exc).split())[:160]}") from None
    if not rows:
        raise ExciteError(
            "data.runs",
            f"no message on {topic} in {path.name} carries every active joint "
            f"({', '.join(joints)}; {skipped} message(s) without some)",
            path,
        )
    if skipped:
        warnings.warn(
            f"{path.name}: {skipped} of {skipped + len(rows)} messages on {topic} carry only some of the active "
            f"joints, and no message stamped within {MERGE_TOLERANCE_S * 1e3:g} ms carries the others: left out "
            "(counted as dropped)",
            ExciteWarning,
        )
    values = np.vstack(rows)
    names = ["time"] + [f"{field}/{joint}" for field in FIELDS for joint in joints]
    filled = [k for k in range(len(names)) if not np.all(np.isnan(values[:, k]))]
    return Table([names[k] for k in filled], values[:, filled], skipped, np.arange(1, values.shape[0] + 1))


def bag_columns(joints: Sequence[str], table: Table) -> dict[str, list[str]]:
    """The columns of a bag's Table by joint name: q from position, q̇ from velocity (if every joint
    has it), τ from effort (the ``data.columns`` a bag needs no one to write)."""
    columns = {"q": [f"position/{j}" for j in joints], "tau": [f"effort/{j}" for j in joints]}
    if all(f"velocity/{j}" in table.names for j in joints):
        columns["qd"] = [f"velocity/{j}" for j in joints]
    return columns
