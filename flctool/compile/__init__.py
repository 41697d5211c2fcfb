"""Compiling a behaviour into frozen arrays, and inference (eq. 1-3)."""

from flctool.compile.controller import Controller, compile_behaviour
from flctool.compile.membership import trapezoid

__all__ = ["Controller", "compile_behaviour", "trapezoid"]
