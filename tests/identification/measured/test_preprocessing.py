"""Preprocessing: the default cut-off from the fitted runs' spectrum, and zero-phase filtering that
keeps a slow signal and removes a fast one."""

from dataclasses import replace

import numpy as np

from excite_cli.identification.config import PreprocessingConfig
from excite_cli.identification.measured.measurements import Run
from excite_cli.identification.measured.preprocessing import MIN_CUTOFF, Filter, choose_cutoff


def test_default_cutoff_from_the_fitted_runs_hann_spectrum():
    rate, t = 1000.0, np.arange(0, 12.0, 0.001)

    def moving(f, crop):
        n = int(crop * rate)
        return Run(
            "m", "fit", t[:n], np.column_stack([np.sin(2 * np.pi * f * t[:n])] * 2), None, None, np.zeros((n, 2))
        )

    static = Run(
        "s", "validation", t, np.random.default_rng(0).normal(0, 1e-3, (t.size, 2)), None, None, np.zeros((t.size, 2))
    )
    cfg = PreprocessingConfig()
    # a 0.8 Hz motion cropped mid-period: 10 x its bandwidth, within the spectrum's resolution (2 bins
    # of 1/7.3 s); the static, noisy validation run has no bandwidth and is not looked at (with it:
    # the cap, 40 % of the 200 Hz rate)
    cutoff, source = choose_cutoff([moving(0.8, 7.3), static], cfg)
    assert 8.0 <= cutoff <= 8.0 + 10 * 2 / 7.3 and "fitted runs" in source
    assert choose_cutoff([replace(static, role="fit")], cfg)[0] == 80.0
    assert choose_cutoff([moving(0.1, 12.0)], cfg)[0] == MIN_CUTOFF  # a slow run: the floor
    assert choose_cutoff([moving(0.8, 7.3)], PreprocessingConfig(cutoff=3.0)) == (3.0, "preprocessing.cutoff")


def test_the_zero_phase_filter_keeps_what_is_slow_and_removes_what_is_fast():
    from scipy import signal

    rate, t = 500.0, np.arange(0, 4.0, 1 / 500.0)
    slow, fast = np.sin(2 * np.pi * 1.0 * t), 0.5 * np.sin(2 * np.pi * 60.0 * t)
    sos = signal.butter(4, 10.0, fs=rate, output="sos")
    out = Filter(sos, rate, 10.0, 0, 1).low_pass((slow + fast)[:, None])[:, 0]
    inner = slice(250, -250)  # away from the ends
    assert np.abs(out[inner] - slow[inner]).max() < 1e-3  # no phase lag, the 60 Hz gone
