"""The contact stepper's state: the foundation's elements, and the instant between steps."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from ..kernels.contact import insert_batch

FREE, CONTACT = 0, 1

#: Phases of the contact (MODEL.md sections 3, 6 and 9).
BONDED = "bonded"  # flat punch, zone outside: a at the rim, b from the edge condition
PINNED = "pinned"  # flat punch, zone on the face: b at the rim, a from the edge condition
CONTACT_PHASE = "contact"  # a and b both free (a recedes, advances or sticks)
ZONE = "zone"  # no contact, the zone alone pulls the surface (a = 0)
FACE = "face"  # flat punch past its face's strength: a = 0, b at the rim until gap(R) = delta
APART = "apart"  # no zone: the surfaces are further apart than delta
DONE = "done"


COLUMNS = ("xi", "Y", "status", "D", "tj", "t_last")


class Nodes:
    """Foundation elements sorted by position ``xi``: the modes ``Y`` of a free element (valid
    at ``t_last``; elements beyond the zone relax unloaded and are brought up to date only
    when the zone reaches them), and for an element in contact the memory ``D`` of its arms
    at the time ``tj`` it joined (see :meth:`pulloff.solvers.contact.Stepper.contact_arms`).

    The first ``n`` are live. Free elements a receding zone left behind may be archived
    (:meth:`archive_beyond`): untouched until a zone reaches them again, they would
    otherwise be shifted by every insertion in front of them (seed_flat_punch leaves tens of
    thousands behind). A trial that reaches ``live_end`` brings them back first
    (:meth:`restore`)."""

    def __init__(self, n_modes: int, n_arms: int, capacity: int = 256):
        self.n = 0
        self._archive = []  # blocks of archived columns, the nearest last
        self.live_end = math.inf  # the nearest archived element
        self.xi = np.zeros(capacity)
        self.Y = np.zeros((capacity, max(n_modes, 1)))
        self.status = np.zeros(capacity, dtype=np.int64)
        self.D = np.zeros((capacity, max(n_arms, 1)))
        self.tj = np.zeros(capacity)
        self.t_last = np.zeros(capacity)
        self.xi_max = -math.inf  # the furthest any element ever was: beyond, the solid is virgin

    def _grow(self):
        for name in COLUMNS:
            old = getattr(self, name)
            new = np.zeros((2 * old.shape[0],) + old.shape[1:], dtype=old.dtype)
            new[:self.n] = old[:self.n]
            setattr(self, name, new)

    @property
    def mesh(self) -> tuple:
        """The columns as the kernels take them (``kernels.contact``'s ``mesh``): read anew
        each time, since growing the arrays replaces them."""
        return (self.xi, self.Y, self.status, self.D, self.tj, self.t_last)

    @property
    def total(self) -> int:
        """Elements live and archived."""
        return self.n + sum(block[0].size for block in self._archive)

    def archive_beyond(self, x: float, at_least: int) -> int:
        """Archive the live elements beyond ``x`` if there are at least ``at_least`` (and
        none is in contact); returns how many went."""
        k = self.below(x)
        if self.n - k < max(at_least, 1) or np.any(self.status[k:self.n] != FREE):
            return 0
        self._archive.append(tuple(getattr(self, name)[k:self.n].copy() for name in COLUMNS))
        moved = self.n - k
        self.n = k
        self.live_end = float(self._archive[-1][0][0])
        return moved

    def restore(self) -> None:
        """Every archived element live again, in place (they lie beyond the live ones)."""
        while self._archive:
            block = self._archive.pop()
            while self.n + block[0].size > self.xi.shape[0]:
                self._grow()
            for name, column in zip(COLUMNS, block):
                getattr(self, name)[self.n:self.n + column.shape[0]] = column
            self.n += block[0].size
        self.live_end = math.inf

    def insert(self, x: float, Y=None, status: int = FREE, D=None, tj: float = 0.0,
               t_last: float = 0.0) -> int:
        """Put an element at ``x`` (kept sorted); returns its index."""
        if x >= self.live_end:
            self.restore()
        if self.n == self.xi.shape[0]:
            self._grow()
        i = int(np.searchsorted(self.xi[:self.n], x))
        for name in COLUMNS:
            arr = getattr(self, name)
            arr[i + 1:self.n + 1] = arr[i:self.n]
        self.xi[i] = x
        self.Y[i] = 0.0 if Y is None else Y
        self.status[i] = status
        self.D[i] = 0.0 if D is None else D
        self.tj[i] = tj
        self.t_last[i] = t_last
        self.n += 1
        self.xi_max = max(self.xi_max, x)
        return i

    def insert_many(self, x: np.ndarray, Y: np.ndarray, status: np.ndarray, D: np.ndarray,
                    tj: np.ndarray, t_last: float) -> None:
        """Put elements at ``x`` (any order; rows of ``Y``, ``D``), as :meth:`insert` one by
        one would, in one compiled merge: a step's new elements once cost a shift of every element
        beyond them each (seed_flat_punch at n = 64 leaves 22000 behind its receding zone:
        a third of the run went into those shifts)."""
        if x.size == 0:
            return
        if np.max(x) >= self.live_end:
            self.restore()
        while self.n + x.size > self.xi.shape[0]:
            self._grow()
        insert_batch((self.xi, self.Y, self.status, self.D, self.tj, self.t_last), self.n,
                     np.ascontiguousarray(x, dtype=float),
                     np.ascontiguousarray(Y, dtype=float),
                     np.ascontiguousarray(status, dtype=np.int64),
                     np.ascontiguousarray(D, dtype=float),
                     np.ascontiguousarray(tj, dtype=float), float(t_last))
        self.n += x.size
        self.xi_max = max(self.xi_max, float(np.max(x)))

    def remove(self, drop: np.ndarray) -> None:
        """Remove the elements whose indices are in ``drop``."""
        keep = np.ones(self.n, dtype=bool)
        keep[drop] = False
        k = int(keep.sum())
        for name in COLUMNS:
            arr = getattr(self, name)
            arr[:k] = arr[:self.n][keep]
        self.n = k

    def near(self, x: float, tol: float) -> bool:
        """Whether an element lies within ``tol`` of ``x``."""
        i = int(np.searchsorted(self.xi[:self.n], x))
        return any(0 <= j < self.n and abs(self.xi[j] - x) <= tol for j in (i - 1, i))

    def below(self, x: float) -> int:
        """Number of elements with ``xi < x``."""
        return int(np.searchsorted(self.xi[:self.n], x))

    def at_most(self, x: float) -> int:
        """Number of elements with ``xi <= x``."""
        return int(np.searchsorted(self.xi[:self.n], x, side="right"))


@dataclass
class Instant:
    """Everything known at one time (dimensionless): lift and its rate, the edges, the phase,
    the forces, the arms' filtered lift ``Hf`` and the running segment."""

    t: float
    H: float
    Hdot: float
    alpha: float
    beta: float
    phase: str
    gap: float = math.nan
    F_contact: float = 0.0
    F_total: float = 0.0
    Hf: np.ndarray = field(default_factory=lambda: np.zeros(0))
    segment: int = 0
    segment_start: float = 0.0
    segment_sign: float = 1.0  # which way the segment's target lies from its start
    centre_u: float = math.nan  # displacement of the element at the centre
    driver: float = 0.0  # where the machine's driver is (behind a spring)

    def copy(self, **changes) -> "Instant":
        changes.setdefault("Hf", self.Hf.copy())
        # (dataclasses.replace re-runs __init__: a tenth of a commit, every step)
        unknown = changes.keys() - self.__dict__.keys()
        if unknown:
            raise TypeError(f"Instant has no field {sorted(unknown)}")
        new = object.__new__(Instant)
        new.__dict__.update(self.__dict__)
        new.__dict__.update(changes)
        return new
