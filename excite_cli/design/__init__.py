"""What is optimized: the excitation problem built from the config, the criterion and its gradient in
the Fourier coefficients, the information it measures, the effect columns and the measured prior, how
a trajectory is played, the gradient check, and the standing robot in MuJoCo that checks balance."""
