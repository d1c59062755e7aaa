"""The robot's model and its dynamics: URDF loading, base parameters, the gradient's RNEA passes, batched kinematics."""
