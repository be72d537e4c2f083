"""Tapping-mode AFM: the impact oscillator FMU coupled with a PI amplitude controller FMU."""
