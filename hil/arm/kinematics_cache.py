"""One `Kinematics` per geometry *content*, kept between calls, for code that evaluates the same arm over
and over (the keep-in box check of every planned leg: `hil.arm.safety.check_target`).

Building a pinocchio model costs about twice what evaluating 16 configurations on it does (a few
hundred microseconds), and route planning asks for the same (nominal, checked-with) geometry some
twenty to forty times per move: `python bench/route_planning.py` halved its CPU time per leg with it.
A `Geometry` is mutable, so the cache is keyed on what a `Kinematics` is built from, byte for byte
(`geometry_key`), never on the object: a geometry changed in place, or another one equal to it, gets
the model its content calls for. A pinocchio ``Data`` is scratch space that every
evaluation writes, so each thread has its own cache (and so its own models and their ``Data``).
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Hashable

import numpy as np

from hil.arm.geometry import Geometry
from hil.arm.kinematics import Kinematics

#: Models kept per thread, least recently used dropped first. A campaign or a MOVEB run checks with one
#: or two geometries; a handful leaves room for a test process that switches arms without rebuilding.
CAPACITY = 8

_local = threading.local()


def geometry_key(geometry: Geometry) -> Hashable:
    """Everything a `Kinematics` reads from `geometry`, exactly (the floats' bytes): two geometries with
    the same key give bit-identical results. The optional blocks (payload, thermal, joint errors) are
    frozen dataclasses, hashed as they are."""
    frames = [*geometry.joints, geometry.flange, geometry.tracker]
    numbers = np.concatenate([*(M.homogeneous.ravel() for M in frames), geometry.smr, geometry.gravity])
    return (geometry.robot, None if geometry.chain is None else geometry.chain.key, numbers.tobytes(),
            None if geometry.compliance is None else geometry.compliance.tobytes(),
            None if geometry.lost_motion is None else geometry.lost_motion.tobytes(),
            geometry.payload, geometry.thermal, geometry.joint_errors)


def _cache() -> OrderedDict[Hashable, Kinematics]:
    cache = getattr(_local, "models", None)
    if cache is None:
        cache = _local.models = OrderedDict()
    return cache


def kinematics_of(geometry: Geometry) -> Kinematics:
    """This thread's `Kinematics` of `geometry`'s current content, built on first use.

    The caller must treat it as read-only (as every `Kinematics` is): it is shared with every later
    call in this thread for an equal geometry.
    """
    key, cache = geometry_key(geometry), _cache()
    kin = cache.get(key)
    if kin is None:
        kin = cache[key] = Kinematics(geometry)
        while len(cache) > CAPACITY:
            cache.popitem(last=False)
    else:
        cache.move_to_end(key)
    return kin


def clear() -> None:
    """Forget this thread's models (tests that count builds start from here)."""
    _cache().clear()
