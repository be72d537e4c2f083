"""Helpers the tests share: FMU builds and runs, CLI calls, FMI probes and the standard's state
tables, edge checks on the exact flow, derivatives, importers and emulated platforms."""
