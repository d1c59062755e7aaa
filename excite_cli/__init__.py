"""excite: persistently exciting trajectories for robot dynamic identification.

Implements Ayusawa et al., "Generating persistently exciting trajectory based on condition
number optimization" (ICRA 2017); equation numbers in docstrings refer to that paper.
"""

__version__ = "0.1.0"
