"""The compiled kernels' machinery: numba wrapper, first-run compile, kernel manifest, worker threads, plain-numpy references of the kernels."""
