"""What a user asks of the joint errors: ``none``, ``auto`` or fixed orders (``--joint-errors``,
``campaign.joint_errors``).

Kept apart from the selection (`hil.calibration.joint_error_selection`) and free of the kinematics, so
reading a station configuration checks the value without loading pinocchio.
"""

from __future__ import annotations

from dataclasses import dataclass

from hil.arm.joint_error_columns import MAX_FIT_ORDER
from hil.errors import InputError

#: What ``--joint-errors`` and ``campaign.joint_errors`` accept besides a list of orders.
MODES: tuple[str, ...] = ("none", "auto")


@dataclass(frozen=True)
class JointErrorRequest:
    """What a user asked for: no joint errors, the cross-validated choice, or fixed orders."""

    mode: str  # "none", "auto" or "orders"
    orders: tuple[int, ...] = ()
    lost_motion: bool = False  # with "orders": the lost motion too, where the data allow it

    def __str__(self) -> str:
        if self.mode != "orders":
            return self.mode
        return ",".join([*map(str, self.orders), *(["lost"] if self.lost_motion else [])])

    @property
    def design_orders(self) -> tuple[int, ...]:
        """The harmonic orders a pose selection should design for: all candidates with "auto"."""
        if self.mode == "none":
            return ()
        return tuple(range(1, MAX_FIT_ORDER + 1)) if self.mode == "auto" else self.orders


def parse_request(text: str, field_name: str = "--joint-errors") -> JointErrorRequest:
    """``none``, ``auto`` or comma-separated orders 1..`MAX_FIT_ORDER`, optionally with ``lost``
    (e.g. ``1,2,lost``); InputError naming `field_name` otherwise."""
    value = str(text).strip().lower()
    if value in MODES:
        return JointErrorRequest(value)
    orders: list[int] = []
    lost = False
    for token in (t.strip() for t in value.split(",")):
        if token == "lost":
            lost = True
        elif token.isdigit() and 1 <= int(token) <= MAX_FIT_ORDER:
            orders.append(int(token))
        else:
            raise InputError(f"{field_name}: {text!r} is not none, auto or orders 1..{MAX_FIT_ORDER} "
                             "with optionally 'lost' (e.g. 1,2,lost)")
    if not orders and not lost:
        raise InputError(f"{field_name}: {text!r} names no order")
    return JointErrorRequest("orders", tuple(sorted(set(orders))), lost)
