"""Named registries: the seams where renderers, estimators, seed policies and statistics plug in.

An entry is an object, or a ``"module:attribute"`` string imported on first use, so that a
registry lists what exists without importing it (the renderers' back ends are heavy). Adding
an implementation is one module plus one :meth:`Registry.register` call; no loop elsewhere
names the entries.

Importing this module pulls in no third-party package.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from importlib import import_module

from .errors import ConfigError


class Registry:
    """Name to implementation, in registration order.

    Parameters
    ----------
    kind : str
        What the entries are (``"renderer"``, ``"estimator"``, ...), for error messages.
    config_key : str, optional
        The config key that selects an entry, named in the error for an unknown name.
    """

    def __init__(self, kind: str, *, config_key: str | None = None):
        self.kind = kind
        self.config_key = config_key
        self._entries: dict[str, object] = {}

    def register(self, name: str, entry: object = None, *, replace: bool = False):
        """Register ``entry`` under ``name``; without ``entry``, a decorator that does.

        Raises
        ------
        ValueError
            ``name`` is taken and ``replace`` is False.
        """
        if entry is None:

            def decorator(obj):
                self.register(name, obj, replace=replace)
                return obj

            return decorator
        if name in self._entries and not replace:
            raise ValueError(f"{self.kind} {name!r} is already registered")
        self._entries[name] = entry
        return entry

    def unregister(self, name: str) -> None:
        """Remove ``name`` (a no-op when it is absent)."""
        self._entries.pop(name, None)

    def get(self, name: str):
        """The entry registered as ``name``, imported on first use.

        Raises
        ------
        ConfigError
            ``name`` is not registered; the one-line message lists the registered names.
        """
        if name not in self._entries:
            where = f"config key '{self.config_key}': " if self.config_key else ""
            raise ConfigError(
                f"{where}unknown {self.kind} {name!r}; use one of: {', '.join(self._entries)}"
            )
        entry = self._entries[name]
        if isinstance(entry, str):
            module, _, attr = entry.partition(":")
            entry = getattr(import_module(module), attr)
            self._entries[name] = entry
        return entry

    def names(self) -> tuple[str, ...]:
        """Registered names, in registration order."""
        return tuple(self._entries)

    def items(self) -> Iterator[tuple[str, object]]:
        """``(name, entry)`` pairs in registration order, each imported."""
        for name in self.names():
            yield name, self.get(name)

    def __contains__(self, name: object) -> bool:
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __len__(self) -> int:
        return len(self._entries)


def factory(registry: Registry) -> Callable[..., object]:
    """``make(name, **options)``: build the registered class or call the factory ``name``."""

    def make(name: str, **options):
        return registry.get(name)(**options)

    return make
