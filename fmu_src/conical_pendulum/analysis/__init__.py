"""Host side: the native reference, fmpy runs compared with it, and sweeps of many runs."""
