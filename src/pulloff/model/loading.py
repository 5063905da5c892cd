"""Loading protocols: how the indenter is driven (MODEL.md sections 1 and 9).

A protocol is data: the solvers read its segments, they do not contain it. Adding a protocol
(or a segment kind) is one class here with a :data:`LOADINGS` row.
"""

from __future__ import annotations

from typing import Annotated, Literal, Optional

from pydantic import BeforeValidator, Field, model_serializer, model_validator

from .fields import Num, bad_line, fmt
from .registry import Kind, Registry

LOADINGS = Registry("loading")


@LOADINGS.register
class ConstantVelocity(Kind):
    """The driver moves as ``h0 + v t``; the indenter follows it rigidly, or through a spring."""

    kind: Literal["constant_velocity"] = Field(description="loading protocol, constant_velocity")
    v: Num = Field(gt=0, description="lift velocity, m/s")
    h0: Num = Field(0.0, ge=0, description="initial lift, m")
    machine_stiffness: Optional[Num] = Field(
        None, gt=0, description="stiffness of the spring between driver and punch, N/m; "
                                "null: a rigid machine")

    @model_validator(mode="after")
    def _spring_starts_relaxed(self) -> ConstantVelocity:
        if self.machine_stiffness is not None and self.h0 != 0:
            raise bad_line(f"{{p}}h0 = {fmt(self.h0)}: with {{p}}machine_stiffness the "
                           "spring starts relaxed at h = 0; a step lift h0 is not defined")
        return self


UNTIL_EVENTS = ("onset", "separation")


def _event_shorthand(v):
    """``until: onset`` is short for ``until: {event: onset}``."""
    return {"event": v} if isinstance(v, str) else v


class Target(Kind):
    """The end of a move: one of a lift, a force, a time or an event."""

    lift: Optional[Num] = Field(None, description="end when the lift reaches this value, m")
    force: Optional[Num] = Field(None, description="end when the total force reaches this "
                                                   "value (tension positive), N")
    time: Optional[Num] = Field(None, gt=0, description="end after this long in the segment, s")
    event: Optional[Literal["onset", "separation"]] = Field(
        None, description="end at the onset of detachment or at complete separation, no unit")

    @model_validator(mode="after")
    def _exactly_one(self) -> Target:
        given = [k for k in ("lift", "force", "time", "event") if getattr(self, k) is not None]
        if len(given) != 1:
            raise bad_line("{k}" + (": empty" if not given else
                           f" = {{{', '.join(given)}}}: more than one end") +
                           " (give one of {lift: m}, {force: N}, {time: s}, onset, separation)")
        return self

    @model_serializer
    def _short(self):
        return self.event if self.event is not None else {self.name: self.value}

    @property
    def name(self) -> str:
        return next(k for k in ("lift", "force", "time", "event") if getattr(self, k) is not None)

    @property
    def value(self):
        return getattr(self, self.name)


class Segment(Kind):
    """One segment of a loading path: a move at constant speed [m/s] (displacement control) or
    constant force rate [N/s] (force control) until a target or an event, or a hold [s]."""

    speed: Optional[Num] = Field(None, description="indenter speed (negative approaches), m/s")
    force_rate: Optional[Num] = Field(None, description="force rate under force control "
                                                        "(tension positive), N/s")
    hold: Optional[Num] = Field(None, gt=0, description="hold the lift (or, under force "
                                                        "control, the force) this long, s")
    until: Annotated[Optional[Target], BeforeValidator(_event_shorthand)] = Field(
        None, description="end of a move: {lift: m}, {force: N}, {time: s}, onset or separation")

    @model_validator(mode="after")
    def _one_drive(self) -> Segment:
        drives = [k for k in ("speed", "force_rate", "hold") if getattr(self, k) is not None]
        if len(drives) != 1:
            raise bad_line("{k}" + (": no drive" if not drives else
                           f" = {{{', '.join(drives)}}}: more than one drive") +
                           " (give one of speed [m/s], force_rate [N/s] or hold [s])")
        if self.hold is not None and self.until is not None:
            raise bad_line(f"{{p}}until = {fmt(self.until.model_dump())}: "
                           "a hold ends after its duration")
        if self.hold is None and self.until is None:
            raise bad_line("{p}until: missing (a move needs an end: {lift: m}, {force: N}, "
                           "{time: s}, onset or separation)")
        rate = self.speed if self.speed is not None else self.force_rate
        if rate == 0.0:
            raise bad_line(f"{{p}}{'speed' if self.speed is not None else 'force_rate'} = 0.0: "
                           "a move that never moves; use hold: DURATION")
        return self

    @property
    def drive(self) -> str:
        return next(k for k in ("speed", "force_rate", "hold") if getattr(self, k) is not None)


@LOADINGS.register
class Path(Kind):
    """A loading path: segments run in order (approach, dwell, retract, ...), under
    displacement control (rigid, or through ``machine_stiffness``) or force control."""

    kind: Literal["path"] = Field(description="loading protocol, path")
    control: Literal["displacement", "force"] = Field(
        "displacement", description="displacement (the lift is driven) or force (the force is "
                                    "driven; speed segments still drive the lift), no unit")
    h0: Num = Field(0.0, description="lift at t = 0, m (negative is pressed in)")
    machine_stiffness: Optional[Num] = Field(
        None, gt=0, description="spring between driver and indenter under displacement control, "
                                "N/m; null: a rigid machine")
    segments: list[Segment] = Field(min_length=1, description="the path's segments, in order")

    @model_validator(mode="after")
    def _drives_fit_the_control(self) -> Path:
        for i, seg in enumerate(self.segments):
            if seg.force_rate is not None and self.control != "force":
                raise bad_line(f"{{p}}segments[{i}].force_rate = {fmt(seg.force_rate)}: only "
                               "under control: force (this path drives the lift)")
        if self.machine_stiffness is not None and self.control == "force":
            raise bad_line(f"{{p}}machine_stiffness = {fmt(self.machine_stiffness)}: a spring "
                           "between driver and indenter only under control: displacement")
        if self.control == "force":
            for i, (seg, after) in enumerate(zip(self.segments, self.segments[1:])):
                apart = seg.until is not None and seg.until.event == "separation"
                if apart and after.speed is None:
                    raise bad_line(f"{{p}}segments[{i + 1}].{after.drive} = "
                                   f"{fmt(getattr(after, after.drive))}: follows a separation "
                                   "under control: force, and a free indenter carries no force "
                                   "(move it with speed: m/s)")
        return self
