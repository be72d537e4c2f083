"""Settings in layers: the defaults, a TOML experiment file (:func:`load_toml`) and the CLI flags,
later ones winning, each value with its origin (:class:`Layered`) so that an error names the flag
or the file key the user wrote."""
from __future__ import annotations

import copy
import os
import sys
from typing import Any, Mapping

from ..errors import HarnessInputError
from .defaults import CLI_FLAGS, DEFAULTS

if sys.version_info >= (3, 11):
    import tomllib
else:  # pragma: no cover
    import tomli as tomllib

__all__ = ["Layered", "load_toml", "PYTHON_ARGS"]

#: The Python argument of the library's entry points (``compare_windows``, ``chart``,
#: ``run_target``) that sets a setting, where it is not the key itself.
PYTHON_ARGS = {("fmu", "path"): "fmu_path"}


class Layered:
    """Nested settings with the origin of each value (for error messages)."""

    def __init__(self) -> None:
        self.values: dict[str, dict[str, Any]] = copy.deepcopy(DEFAULTS)
        self.origin: dict[tuple[str, str], str] = {}

    def merge(self, layer: Mapping[str, Mapping[str, Any]], source: str) -> None:
        """Overlay ``layer`` (``{section: {key: value}}``); ``source`` is ``"cli"`` or a file name.

        Unknown sections and keys are rejected (except in ``[model]``, whose keys are FMU
        variables checked later against the modelDescription).
        """
        from ..errors import ErrorCollector

        found = ErrorCollector()  # every unknown section and key of the layer, not just the first
        for section, entries in layer.items():
            if section not in DEFAULTS:
                found.add(HarnessInputError(
                    f"{source}: [{section}]",
                    f"unknown section; known sections: {', '.join(DEFAULTS)}",
                ))
                continue
            if not isinstance(entries, Mapping):
                found.add(HarnessInputError(f"{source}: {section}", "must be a table"))
                continue
            for key, value in entries.items():
                if section != "model" and key not in DEFAULTS[section]:
                    found.add(HarnessInputError(
                        f"{source}: {section}.{key}",
                        f"unknown key; known keys of [{section}]: {', '.join(DEFAULTS[section])}",
                    ))
                    continue
                if value is None:
                    continue  # "not given": keeps the lower layer
                self.values[section][key] = value
                self.origin[(section, key)] = source
        found.raise_if_any()

    def arg(self, section: str, key: str) -> str:
        """How to name ``section.key`` in an error: its CLI flag, its file key, or (a value a
        Python caller passed, origin ``"api"``) the Python argument."""
        src = self.origin.get((section, key))
        if src == "cli":
            return CLI_FLAGS.get((section, key), f"--{key.replace('_', '-')}")
        if src == "api":
            return PYTHON_ARGS.get((section, key), key)
        if src is None:
            return f"{section}.{key}"
        return f"{src}: {section}.{key}"

    def get(self, section: str, key: str) -> Any:
        """The current value of ``section.key``."""
        return self.values[section][key]

    def given(self, section: str, key: str) -> bool:
        """Whether ``section.key`` was set by a file, a flag or a Python argument (not a default)."""
        return (section, key) in self.origin


def load_toml(path: str | os.PathLike, argument: str = "--config") -> dict[str, Any]:
    """Read an experiment file, turning I/O and syntax problems into clear errors."""
    try:
        with open(path, "rb") as fh:
            return tomllib.load(fh)
    except FileNotFoundError:
        raise HarnessInputError(argument, f"no such file: {str(path)!r}") from None
    except IsADirectoryError:
        raise HarnessInputError(argument, f"{str(path)!r} is a directory, not an experiment file") from None
    except UnicodeDecodeError as exc:  # TOML is UTF-8 by definition
        raise HarnessInputError(argument, f"{path} is not UTF-8 text (byte {exc.start}: {exc.reason})") from None
    except tomllib.TOMLDecodeError as exc:
        raise HarnessInputError(argument, f"{path} is not valid TOML: {exc}") from None
    except OSError as exc:  # permission denied, I/O errors
        raise HarnessInputError(argument, f"cannot read {str(path)!r}: {exc.strerror or exc}") from None
