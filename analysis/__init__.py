"""Loads post-processing on recovered histories, callable from Python without the
application (issue 24): spectra (SRS, PSD, FFT, the acceleration band), statistics
(k-factors, order statistics, streaming accumulators) and the streamed aggregation of a
campaign's records. numpy/scipy (+numba) only, like reduction/ and transient/: it runs on
histories from elsewhere. SI units in and out.
"""
