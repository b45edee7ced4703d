"""The controller types empact designs, by name: the one registry the command line's
``empact control design --method`` choices come from.

A type is its design function, ``design(family, bandwidth_hz, **options) -> Controller``,
named ``"module:function"`` and imported when first used (so that listing the names loads
neither python-control nor the synthesis code).  The defaults are the design function's own
(its signature): the command line passes only the options a user gives, so its defaults are
the API's by construction.  They are the recipe of the shipped designs
(``data/control/pi.json`` and ``hinf.json``, `empact.reproduction.control.SHIPPED_DESIGNS`).

To add a controller type: write its design function (a module of `empact.control`, returning
a `empact.control.controller.Controller` whose ``design`` dict records what it reached) and
add one entry to `CONTROLLER_TYPES`; ``empact control design --method NAME`` then offers it.
"""
from __future__ import annotations

import importlib
import inspect
from dataclasses import dataclass
from typing import Any, Callable

from ..errors import ParameterError

__all__ = ["ControllerType", "CONTROLLER_TYPES", "controller_type"]


@dataclass(frozen=True)
class ControllerType:
    """One controller type of the registry.

    Attributes
    ----------
    name : str
        The name the command line offers (``--method NAME``).
    function : str
        Its design function as ``"module:function"``.
    summary : str
        One line for the command's help.
    """

    name: str
    function: str
    summary: str

    def design_function(self) -> Callable[..., Any]:
        """The design function (imported on first use)."""
        module, attr = self.function.split(":")
        return getattr(importlib.import_module(module), attr)

    def defaults(self) -> dict[str, Any]:
        """The design function's keyword defaults by name (``bandwidth_hz`` [Hz], ...)."""
        sig = inspect.signature(self.design_function())
        return {k: p.default for k, p in sig.parameters.items()
                if p.default is not inspect.Parameter.empty}

    def accepts(self, option: str) -> bool:
        """Whether the design function takes the keyword `option`.

        Parameters
        ----------
        option : str
            A keyword argument name (``"alpha_min"``, ``"bandwidth"``, ...).

        Returns
        -------
        bool
            True where the registered design function accepts it.
        """
        return option in inspect.signature(self.design_function()).parameters


#: the controller types by name, in the order the command line lists them
CONTROLLER_TYPES: dict[str, ControllerType] = {
    "pi": ControllerType("pi", "empact.control.pi:design_pi",
                         "decentralised PI checked on the loop that runs (gain-scheduled by "
                         "default on the command line)"),
    "hinf": ControllerType("hinf", "empact.control.hinf:design_hinf",
                           "multi-model H-infinity (S / KS / T mixed sensitivity) of a "
                           "structured 8-state MIMO controller over every plant, on the loop "
                           "that runs (gain-scheduled by default on the command line)"),
}


def controller_type(name: str) -> ControllerType:
    """The registered controller type called `name`.

    Parameters
    ----------
    name : str
        A key of `CONTROLLER_TYPES` (``"pi"``, ``"hinf"``).

    Returns
    -------
    ControllerType
        Its design function and the options it takes.

    Raises
    ------
    ParameterError
        If `name` is not registered (the message names the choices).
    """
    try:
        return CONTROLLER_TYPES[name]
    except KeyError:
        raise ParameterError(f"controller type {name!r}: choose one of "
                             f"{', '.join(CONTROLLER_TYPES)}") from None
