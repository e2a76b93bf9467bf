"""Loading the user's own stereo network: the factory it names, its weights, its device.

``--model`` names a callable without arguments that builds a :class:`torch.nn.Module`:
``package.module:factory``, imported like ``python -m`` imports (the current folder first, so
a plain ``nets.py`` beside the user is ``nets:build``), or ``path/to/file.py:factory``, run
from its file. ``--weights`` is its ``state_dict`` saved with ``torch.save`` (or a checkpoint
dict holding it as ``"state_dict"``), read with ``torch.load(weights_only=True)`` and loaded
strictly. Every way this can fail stops in one line naming the fix (:class:`ModelError`).

Importing this module imports PyTorch (the ``probe`` extra).
"""

from __future__ import annotations

import importlib
import importlib.util
import os
import stat
import sys
from pathlib import Path

import torch

from ..errors import StereovarError
from ..io.files import file_kind

__all__ = [
    "FACTORY_FORMAT",
    "WEIGHTS_SUFFIXES",
    "ModelError",
    "check_weights_file",
    "load_user_model",
    "search_current_folder",
]

WEIGHTS_SUFFIXES = (".pt", ".pth", ".ckpt", ".tar", ".bin")
"""Usual extensions of a file written by ``torch.save`` (offered from a folder given as
weights)."""

FACTORY_FORMAT = "package.module:factory (or path/to/file.py:factory)"
"""The forms of ``--model``, as the one-line errors name them."""


class ModelError(StereovarError):
    """The user's model cannot be imported, built, loaded or run as the probe needs it; the
    message is one line naming the fix."""


def _one_line(err: BaseException) -> str:
    text = " ".join(str(err).split())
    return f"{type(err).__name__}: {text}" if text else type(err).__name__


def _split_factory(spec: str) -> tuple[str, str]:
    """``module:attribute`` of a factory spec; one line when it has another form.

    Examples
    --------
    >>> _split_factory("mypkg.models:build")
    ('mypkg.models', 'build')
    """
    module, sep, attr = str(spec).rpartition(":")
    if not sep or not module or not attr or not all(p.isidentifier() for p in attr.split(".")):
        raise ModelError(f"model {spec!r} is not {FACTORY_FORMAT}; give e.g. mypkg.nets:build")
    return module, attr


def search_current_folder() -> str | None:
    """Put the current folder first on the import path, where it is not on it already, as
    ``python -m`` does: ``--model nets:build`` then finds ``./nets.py`` (and ``./mypkg/``)
    when the command is an installed script, whose own folder is the one Python searches.

    Returns
    -------
    str or None
        The current folder, or None where it no longer exists.
    """
    try:
        here = os.getcwd()
    except OSError:  # the folder was removed under the process
        return None
    if not any(os.path.abspath(p or os.curdir) == here for p in sys.path):
        sys.path.insert(0, here)
    importlib.invalidate_caches()
    return here


def _import_module(module: str):
    if module.endswith(".py"):
        path = Path(module)
        if not path.is_file():
            raise ModelError(f"model file {module} does not exist; give an existing .py file")
        name = f"_stereovar_user_model_{abs(hash(str(path.resolve())))}"
        spec = importlib.util.spec_from_file_location(name, path)
        mod = importlib.util.module_from_spec(spec)
        try:
            sys.modules[name] = mod
            spec.loader.exec_module(mod)
        except Exception as err:
            sys.modules.pop(name, None)
            raise ModelError(
                f"model file {module} does not import ({_one_line(err)}); run it with python "
                "to see the traceback"
            ) from None
        return mod
    here = search_current_folder()
    try:
        return importlib.import_module(module)
    except ModuleNotFoundError as err:
        if err.name and (module == err.name or module.startswith(f"{err.name}.")):
            raise ModelError(_not_found(module, err, here)) from None
        raise ModelError(
            f"model module {module!r} does not import ({_one_line(err)}); install the package "
            f"it imports ({err.name}) or add its folder to PYTHONPATH"
        ) from None
    except Exception as err:
        raise ModelError(
            f"model module {module!r} does not import ({_one_line(err)}); run python -c "
            f"'import {module}' in this folder to see the traceback"
        ) from None


def _not_found(module: str, err: ModuleNotFoundError, here: str | None) -> str:
    """One line: the model's module (or its package) is neither in the current folder nor
    installed; the fixes."""
    where = f"the current folder {here}" if here else "the current folder (it was removed)"
    own = f"{module.replace('.', '/')}.py"
    return (
        f"model module {module!r} does not import ({_one_line(err)}): {err.name} is found "
        f"neither in {where} nor elsewhere on the import path; run stereovar from the folder "
        f"that holds {own}, give its path ({own}:factory), install its package, or add its "
        "folder to PYTHONPATH"
    )


def _factory(spec: str):
    module, attr = _split_factory(spec)
    obj = _import_module(module)
    for part in attr.split("."):
        if not hasattr(obj, part):
            raise ModelError(
                f"model module {module!r} has no attribute {attr!r}; name the function or "
                f"class that builds the model ({FACTORY_FORMAT})"
            )
        obj = getattr(obj, part)
    if not callable(obj):
        raise ModelError(f"model factory {spec!r} is not callable; name a function or class")
    return obj


def _state_dict(payload, weights) -> dict:
    if isinstance(payload, dict) and isinstance(payload.get("state_dict"), dict):
        payload = payload["state_dict"]
    if not isinstance(payload, dict) or not all(
        isinstance(v, torch.Tensor) for v in payload.values()
    ):
        raise ModelError(
            f"weights file {weights} holds no state_dict (a dict of tensors, or a dict with "
            "'state_dict'); save it with torch.save(model.state_dict(), FILE)"
        )
    return payload


def check_weights_file(weights) -> Path:
    """``weights`` as a path, once it is known to be a regular file (a link to one counts);
    nothing is opened, so a named pipe is refused without waiting on it.

    Parameters
    ----------
    weights : str or path

    Returns
    -------
    pathlib.Path

    Raises
    ------
    ModelError
        One line: the path does not exist, cannot be looked at, is a directory (naming the
        weights files inside it, if any), or is a named pipe, a device or a socket
        (:func:`stereovar.io.files.file_kind`).
    """
    path = Path(weights)
    try:
        mode = os.stat(path).st_mode
    except FileNotFoundError:
        raise ModelError(
            f"weights file {path} does not exist; give the model's saved weights"
        ) from None
    except OSError as err:
        raise ModelError(
            f"weights file {path} cannot be looked at ({err.strerror or err}); give a readable "
            "path to the model's saved weights"
        ) from None
    if stat.S_ISDIR(mode):
        raise ModelError(f"weights {path} is a directory; {_inside(path)}")
    if not stat.S_ISREG(mode):
        raise ModelError(
            f"weights {path} is {file_kind(mode)}, not a file; give the model's weights file "
            "saved with torch.save"
        )
    return path


def _inside(folder: Path) -> str:
    """The fix for a folder given as weights: the file inside it to give, named where the
    folder holds files with a :data:`WEIGHTS_SUFFIXES` extension."""
    try:
        found = sorted(
            p for p in folder.iterdir() if p.suffix.lower() in WEIGHTS_SUFFIXES and p.is_file()
        )
    except OSError:
        found = []
    if not found:
        return "give the weights file inside it (the file torch.save wrote, e.g. model.pt)"
    listed = ", ".join(str(p) for p in found[:3]) + (", ..." if len(found) > 3 else "")
    return f"give the weights file inside it: {listed}"


def load_user_model(factory: str, weights, *, device: str = "cpu") -> torch.nn.Module:
    """The user's model: ``factory()`` with the weights of ``weights``, in eval mode.

    Parameters
    ----------
    factory : str
        ``package.module:factory`` (or ``path/to/file.py:factory``): a callable without
        arguments that returns a :class:`torch.nn.Module`. The module is imported with the
        current folder first on the import path (:func:`search_current_folder`).
    weights : str or path
        A file saved with ``torch.save``: the model's ``state_dict``, or a dict holding it as
        ``"state_dict"``; read with ``torch.load(weights_only=True)``.
    device : str, keyword-only

    Returns
    -------
    torch.nn.Module

    Raises
    ------
    ModelError
        One line each: the weights file is missing or not a file (:func:`check_weights_file`),
        the spec is malformed, the module does not import, it has no such attribute, the
        factory raises or returns no module, the weights do not load or do not fit the model.
    """
    weights = check_weights_file(weights)
    build = _factory(factory)
    try:
        model = build()
    except Exception as err:
        raise ModelError(
            f"model factory {factory!r} raised {_one_line(err)}; it must build the model "
            "without arguments (wrap it in a function that passes them)"
        ) from None
    if not isinstance(model, torch.nn.Module):
        raise ModelError(
            f"model factory {factory!r} returned {type(model).__name__}, not a torch.nn.Module"
        )
    try:
        payload = torch.load(weights, map_location="cpu", weights_only=True)
    except Exception as err:
        raise ModelError(
            f"weights file {weights} does not load with torch.load(weights_only=True) "
            f"({_one_line(err)}); save the state_dict with torch.save"
        ) from None
    state = _state_dict(payload, weights)
    try:
        model.load_state_dict(state)
    except Exception as err:
        raise ModelError(
            f"weights file {weights} does not fit the model of {factory!r} ({_one_line(err)})"
        ) from None
    return model.to(_device(device)).eval()


def _device(device) -> torch.device:
    """``device`` as a torch device PyTorch can use here, else one line."""
    try:
        dev = torch.device(device)
    except (RuntimeError, TypeError) as err:
        raise ModelError(
            f"device {device!r} is not a torch device ({_one_line(err)}); use cpu, cuda or "
            "cuda:N"
        ) from None
    if dev.type == "cuda" and not torch.cuda.is_available():
        raise ModelError(
            f"device {device!r}: PyTorch sees no CUDA GPU here (torch {torch.__version__}); "
            "use --device cpu, or a machine with a GPU and a CUDA build of PyTorch"
        )
    return dev
