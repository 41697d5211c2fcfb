"""flctool's version, in a module of its own: files flctool writes name it, and any module may
import it without importing the package's public face (:mod:`flctool`)."""

__version__ = "0.1.0"
