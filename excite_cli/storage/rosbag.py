"""ROS 2 bags excite writes (a folder: ``metadata.yaml`` and an SQLite3 file, rosbag2 format version
8, written with ``rosbags``, no ROS installation), whole or not at all.

An exported motion: one ``trajectory_msgs/msg/JointTrajectory``
on a joint trajectory controller's command topic, with one point per sample (positions [rad],
velocities [rad/s], accelerations [rad/s²], time_from_start; effort [Nm], the feed-forward torque,
only when asked: see :mod:`excite_cli.storage.trajectory_controller`) and a header stamp of 0 (start
on arrival). ``ros2 bag play BAG`` publishes it; ``--remap`` sends it
to another controller. A goal for ``ros2 action send_goal`` is one command-line argument, which Linux
caps at 128 KiB (``MAX_ARG_STRLEN``): longer goals are refused in favour of the bag.

A simulated run, as ``ros2 bag record /joint_states`` writes one: a ``sensor_msgs/msg/JointState``
per sample on :data:`JOINT_STATES`, stamped with its time (from :data:`START`), joints by name,
``position`` [rad] and ``effort`` [Nm] filled, ``velocity`` empty (what many drivers publish).
"""

from __future__ import annotations

import sqlite3
import time
from pathlib import Path
from typing import Sequence

import numpy as np
import yaml
from rosbags.rosbag2 import Writer, WriterError
from rosbags.typesys import Stores, get_typestore

from excite_cli.atomic import MARK, atomic_folder, atomic_folders, is_mark
from excite_cli.errors import CannotWrite, ExciteError, OutputExists
from excite_cli.storage.paths import check_target
from excite_cli.storage.trajectory_controller import time_from_start_ns

#: The topic a ros2_control joint trajectory controller named ``joint_trajectory_controller`` listens on.
TOPIC = "/joint_trajectory_controller/joint_trajectory"
MSGTYPE = "trajectory_msgs/msg/JointTrajectory"
#: ``ros2 bag play --delay`` [s]: the bag holds one message, published the instant the player starts,
#: before discovery has matched the controller's subscription; the delay lets it match first.
PLAY_DELAY_S = 2.0
#: ``ros2 bag play --wait-for-all-acked`` [ms] (rosbag2 since Humble): the player waits until the
#: controller has acknowledged the message (reliable QoS) before it ends.
ACKED_WAIT_MS = 5000
#: The joint-state topic robots publish and ``ros2 bag record`` records.
JOINT_STATES = "/joint_states"
#: Stamp of a simulated run's first sample [ns] (2026-01-01, Unix time: a recording's clock).
START = 1_767_225_600 * 10**9
#: The key of the bag's metadata ``custom_data`` (rosbag2 metadata version 6 on) under which excite marks
#: the bags it writes (:data:`~excite_cli.atomic.MARK`): ``ros2 bag record`` writes no such key.
CUSTOM_DATA_KEY = "written_by"
#: Longest single command-line argument on Linux [bytes] (``MAX_ARG_STRLEN``, 32 pages of 4 KiB).
MAX_ARGUMENT = 131_072


def check_goal_size(text: str) -> None:
    """A FollowJointTrajectory goal given as one command-line argument fits Linux's limit.

    Raises:
        ExciteError: (``format``) the goal is longer than :data:`MAX_ARGUMENT`, naming the bag route.
    """
    size = len(text.encode("utf-8"))
    if size > MAX_ARGUMENT:
        raise ExciteError(
            "format",
            f"the ros2 goal is {size / 1024:.0f} KiB, more than the 128 KiB one command-line argument holds "
            '(ros2 action send_goal … "$(cat FILE)" would fail: Argument list too long)',
            "ros2",
            "the rosbag2 format (played with ros2 bag play), or a lower rate",
        )


def is_rosbag2_folder(folder: Path, excite: bool = False) -> bool:
    """Whether ``folder`` is a ROS 2 bag and nothing else: its ``metadata.yaml`` parses as rosbag2's
    (``rosbag2_bagfile_information`` with ``relative_file_paths``, the rosbag2 metadata format) and the
    folder holds no file or folder but that metadata and the files it lists (what excite, or ``ros2 bag
    record``, wrote there). A folder holding anything else is a user's, however its files are named.
    With ``excite``: and excite wrote it (its ``custom_data`` holds :data:`CUSTOM_DATA_KEY` with excite's
    mark), not ``ros2 bag record`` (a lab's recording)."""
    try:
        info = yaml.safe_load((folder / "metadata.yaml").read_text(encoding="utf-8"))["rosbag2_bagfile_information"]
        listed = {str(name) for name in info["relative_file_paths"]}
        mark = str((info.get("custom_data") or {}).get(CUSTOM_DATA_KEY, ""))
    except (OSError, UnicodeDecodeError, yaml.YAMLError, KeyError, TypeError, AttributeError):
        return False
    only_the_bag = {entry.name for entry in folder.iterdir()} <= listed | {"metadata.yaml"}
    return only_the_bag and (not excite or is_mark(mark))


def check_bag_target(folder: Path, field: str, force: bool) -> Path:
    """``folder`` may receive a bag: it does not exist, or with ``force`` it is a bag excite wrote and
    nothing else (:func:`is_rosbag2_folder`), which is replaced; never a lab's recording, another folder
    or a file.

    Raises:
        OutputExists: it exists (or a symbolic link is there), without ``force``.
        ExciteError: it is a file, a folder that is not only a bag excite wrote, a symbolic link, or
            cannot be written (:func:`~excite_cli.storage.paths.check_target`).
    """
    folder = Path(folder)
    if (folder.exists() or folder.is_symlink()) and not force:
        raise OutputExists(field, folder)
    if folder.is_symlink():
        raise ExciteError(
            field, f"{folder} is a symbolic link; a bag is not written through it", folder, "a new folder"
        )
    if folder.exists() and not (folder.is_dir() and is_rosbag2_folder(folder)):
        raise ExciteError(
            field,
            f"{folder} exists and is not only a ROS 2 bag (a rosbag2 metadata.yaml and the files it lists); "
            "not replaced",
            folder,
            "a new folder",
        )
    if folder.exists() and not is_rosbag2_folder(folder, excite=True):
        raise ExciteError(
            field,
            f"{folder} is a ROS 2 bag excite did not write (a recording); not replaced",
            folder,
            "a new folder (or remove it yourself)",
        )
    check_target(folder / "metadata.yaml", field, force=True, exists_ok=True)  # writable (the bag: checked above)
    return folder


def _message(
    types: dict, joints: list[str], time_s: np.ndarray, motion: tuple[np.ndarray, ...], effort: bool
) -> object:
    """The JointTrajectory of one point per instant of ``time_s`` (S,) [s]: ``motion`` q, q̇, q̈, τ (S, n),
    τ as effort only with ``effort`` (``types``: a typestore's message classes)."""
    Time, Duration = (types[f"builtin_interfaces/msg/{t}"] for t in ("Time", "Duration"))
    Header, Point = types["std_msgs/msg/Header"], types["trajectory_msgs/msg/JointTrajectoryPoint"]
    q, qd, qdd, tau = motion
    nanoseconds = time_from_start_ns(time_s)
    none = np.zeros(0)
    points = [
        Point(
            positions=q[k],
            velocities=qd[k],
            accelerations=qdd[k],
            effort=tau[k] if effort else none,
            time_from_start=Duration(sec=int(ns // 10**9), nanosec=int(ns % 10**9)),
        )
        for k, ns in enumerate(nanoseconds)
    ]
    header = Header(stamp=Time(sec=0, nanosec=0), frame_id="")
    return types[MSGTYPE](header=header, joint_names=list(joints), points=points)


def _write_bag(folder: Path, topic: str, msgtype: str, messages) -> Path:
    """``messages`` ((recording time [ns], message) pairs) on ``topic`` as a bag at ``folder``, whole
    or not at all (:func:`~excite_cli.atomic.atomic_folder`; an existing bag there is replaced, see
    :func:`check_bag_target`).

    Raises:
        CannotWrite: the bag cannot be written (a full disk, permissions), whatever the writer or its
            storage raises; nothing is left of it and a bag it was to replace is kept.
    """
    with atomic_folder(folder) as staging:
        _fill_bag(staging, folder, topic, msgtype, messages)
    return Path(folder)


def _fill_bag(staging: Path, folder: Path, topic: str, msgtype: str, messages) -> None:
    """The bag of :func:`_write_bag` written at ``staging`` (which does not exist yet) for ``folder``.

    Raises:
        CannotWrite: (naming ``folder``) what rosbags' writer or its SQLite storage raises.
    """
    typestore = get_typestore(Stores.ROS2_HUMBLE)
    try:
        with Writer(staging, version=8) as writer:
            writer.set_custom_data(CUSTOM_DATA_KEY, MARK)
            connection = writer.add_connection(topic, msgtype, typestore=typestore)
            for ns, message in messages(typestore.types):
                writer.write(connection, ns, typestore.serialize_cdr(message, msgtype))
    except (WriterError, sqlite3.Error) as exc:  # rosbags' own, and its SQLite storage's (a full disk at close)
        raise CannotWrite("output", folder, exc) from None


def write_rosbag(
    folder: Path,
    joints: list[str],
    time_s: np.ndarray,
    motion: tuple[np.ndarray, ...],
    topic: str = TOPIC,
    effort: bool = False,
) -> Path:
    """Write a played motion (``time_s`` (S,) [s] from 0; ``motion`` q, q̇, q̈, τ (S, n) [rad, rad/s,
    rad/s², Nm] of ``joints``) as the trajectory bag of the module docstring at ``folder``
    (:func:`_write_bag`), τ as the points' effort only with ``effort``.

    Raises:
        CannotWrite: the bag cannot be written.
    """
    return _write_bag(
        folder, topic, MSGTYPE, lambda types: [(time.time_ns(), _message(types, joints, time_s, motion, effort))]
    )


def write_joint_states(
    folders: Sequence[Path], joints: list[str], runs: Sequence[tuple[np.ndarray, np.ndarray, np.ndarray]]
) -> list[Path]:
    """Write runs (each ``time_s`` (T,) [s] from 0, ``q``, ``tau`` (T, n) [rad, Nm] of ``joints``) as the
    recorded bags of the module docstring at ``folders``, one a run, all or none
    (:func:`~excite_cli.atomic.atomic_folders`: the bags they replace are kept until every new one is
    written).

    Raises:
        CannotWrite: a bag cannot be written; none is, and the earlier ones stay.
    """

    def messages(time_s: np.ndarray, q: np.ndarray, tau: np.ndarray):
        def each(types):
            Time, Header, JointState = (
                types[t] for t in ("builtin_interfaces/msg/Time", "std_msgs/msg/Header", "sensor_msgs/msg/JointState")
            )
            for k, ns in enumerate(START + np.round(time_s * 1e9).astype(np.int64)):
                header = Header(stamp=Time(sec=int(ns // 10**9), nanosec=int(ns % 10**9)), frame_id="")
                yield (
                    int(ns),
                    JointState(header=header, name=list(joints), position=q[k], velocity=np.zeros(0), effort=tau[k]),
                )

        return each

    with atomic_folders(folders, "output_dir") as stagings:
        for staging, folder, run in zip(stagings, folders, runs):
            _fill_bag(staging, folder, JOINT_STATES, "sensor_msgs/msg/JointState", messages(*run))
    return [Path(f) for f in folders]
