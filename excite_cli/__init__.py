"""excite: persistently exciting trajectories for robot dynamic identification.

Implements Ayusawa et al., "Generating persistently exciting trajectory based on condition
number optimization" (ICRA 2017); equation numbers in docstrings refer to that paper.

Importing it before NumPy gives the same arithmetic on every x86-64 processor (:mod:`excite_cli.kernels`).
"""

from excite_cli.kernels import use_common_kernels

__version__ = "0.1.0"
use_common_kernels()
