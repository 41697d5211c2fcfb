"""Compiling a behaviour into frozen arrays, and inference (eq. 1-3).

The names below are imported on first use, so that the plain-Python parts of this package
(:mod:`flctool.compile.rules`, :mod:`flctool.compile.sparse`, :mod:`flctool.compile.defuzzify`)
can be used without loading numpy (``flctool infer`` on a small table does), as can the
membership functions below this package (:func:`flctool.membership.firing_sets`).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from flctool.lazy import lazy_attributes

if TYPE_CHECKING:
    from flctool.compile.controller import Controller, compile_behaviour

__all__ = ["Controller", "compile_behaviour"]

_HOMES = {"Controller": "flctool.compile.controller",
          "compile_behaviour": "flctool.compile.controller"}


__getattr__ = lazy_attributes(__name__, _HOMES)
