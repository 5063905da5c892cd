"""Registries of model kinds: one class per kind, one row per class.

Each family (geometry, rheology, adhesion, loading) is a :class:`Registry`. A kind is a small
pydantic class whose ``kind`` field is a one-value ``Literal``; registering it is all it takes
for the scene schema (a discriminated union built by :meth:`Registry.union`), the error
messages and the parametrised tests to know it.
"""

from __future__ import annotations

import typing
from typing import Annotated, ClassVar, Union

from pydantic import BaseModel, ConfigDict, Field


class Kind(BaseModel):
    """Base of every registered kind: unknown keys are errors, never silently dropped."""

    model_config = ConfigDict(extra="forbid")

    #: The keys of a typical instance (besides ``kind``): what the parametrised tests over a
    #: registry build, so a new kind is tested by adding its row.
    example: ClassVar[dict] = {}

    @classmethod
    def kind_name(cls) -> str:
        (name,) = typing.get_args(cls.model_fields["kind"].annotation)
        return name

    @classmethod
    def parameters(cls) -> list[str]:
        """The keys a scene gives for this kind, besides ``kind``."""
        return [name for name in cls.model_fields if name != "kind"]


class Registry:
    """``kind`` name -> class, in registration order (the order users see in messages)."""

    def __init__(self, family: str):
        self.family = family
        self._kinds: dict[str, type[Kind]] = {}

    def register(self, cls: type[Kind]) -> type[Kind]:
        """Class decorator: add ``cls`` under its ``kind`` literal."""
        name = cls.kind_name()
        if name in self._kinds:
            raise ValueError(f"{self.family} kind {name!r} registered twice")
        self._kinds[name] = cls
        return cls

    def __getitem__(self, name: str) -> type[Kind]:
        return self._kinds[name]

    def __contains__(self, name: str) -> bool:
        return name in self._kinds

    def __iter__(self):
        return iter(self._kinds.values())

    def names(self) -> list[str]:
        return list(self._kinds)

    def union(self, description: str):
        """The annotation of a scene section holding any registered kind (a discriminated
        union on ``kind``, so an error names the kind's own keys)."""
        classes = tuple(self._kinds.values())
        member = classes[0] if len(classes) == 1 else Union[classes]  # noqa: UP007
        if len(classes) == 1:
            return Annotated[member, Field(description=description)]
        return Annotated[member, Field(discriminator="kind", description=description)]
