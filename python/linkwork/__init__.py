"""Linkwork: planar multibody kinematics.

A Rust engine with a thin Python layer on top::

    import linkwork

    model = linkwork.load("examples/quick_return_a.yaml")
    print(model.check()["mechanism"]["dof"])   # 1: the crank
    results = model.run()                      # the first analysis in the file
    results["rocker.phi"]                      # numpy array, one value per output time
    results.to_pandas()                        # DataFrame indexed by time (needs pandas)
    results.write("out/quick_return_a")        # results.csv and summary.json

Errors are exceptions under :class:`LinkworkError`; see :mod:`linkwork.errors`.
"""

from __future__ import annotations

import json
import os
from collections.abc import Mapping
from typing import Any

from . import _linkwork, errors
from .errors import *  # noqa: F403 (the exception classes: errors.__all__)
from ._entries import ByLengths, CamProfile, ContactFriction, PinFriction, Shape, SlideFriction
from .builder import Body, Mechanism
from .model import Model
from .results import Results
from .summary import Summary
from .sweep import sweep
from .tolerance import tolerance

__version__: str = _linkwork.__version__

__all__ = [
    "Body",
    "ByLengths",
    "CamProfile",
    "ContactFriction",
    "Mechanism",
    "Model",
    "PinFriction",
    "Results",
    "Shape",
    "SlideFriction",
    "Summary",
    "__version__",
    "from_yaml",
    "load",
    "schema",
    "sweep",
    "tolerance",
]
__all__ += errors.__all__


def __dir__() -> list[str]:
    """``dir(linkwork)``: the public API, :data:`__all__` (not the submodules and names the
    package imports for itself, which stay importable)."""
    return sorted(__all__)


def load(path: str | os.PathLike[str], parameters: Mapping[str, float | str] | None = None) -> Model:
    """Read and compile the model file at ``path``, with ``parameters`` over the values of its
    ``parameters:`` section (a number is SI; a string may carry a unit, ``"300 mm"``).

    Raises :class:`ModelError` (with every problem in ``problems``) if the file is invalid, and
    :class:`FileError` (also an :class:`OSError`) if it cannot be read.
    """
    return Model.load(path, parameters)


def from_yaml(text: str, parameters: Mapping[str, float | str] | None = None) -> Model:
    """Compile a model from the text of a model file (YAML), with ``parameters`` as in
    :func:`load`."""
    return Model.from_yaml(text, parameters)


def schema() -> dict[str, Any]:
    """The JSON Schema of model files, as a dict (``linkwork schema`` prints it as JSON)."""
    result: dict[str, Any] = json.loads(_linkwork.schema())
    return result
