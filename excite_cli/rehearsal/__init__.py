"""Physics rehearsal: an export played in MuJoCo on the lab's robot and controller before the robot moves."""
