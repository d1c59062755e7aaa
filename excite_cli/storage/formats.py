"""The export's file formats, without what writes them (the command line's help lists them at
start-up; :mod:`~excite_cli.storage.export` writes them)."""

#: File formats and their file-name endings (``ros2``: a FollowJointTrajectory goal as YAML;
#: ``rosbag2``: a ROS 2 bag, a folder without an ending).
FORMATS = {"csv": "csv", "npz": "npz", "ros2": "yaml", "rosbag2": ""}
