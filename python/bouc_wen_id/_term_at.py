"""``Term.at``: one name for a term's class at a place and for a term (with its value) at a place.

Outside the registry package (terms/): its modules are the protocol and the terms only (tests/test_terms.py).
Before, ``at`` was a classmethod, and ``Viscous(0.03).at(Place.X)`` returned the class and dropped 0.03
without a word (review 32).
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Optional, Union, overload

if TYPE_CHECKING:
    from .terms._base import Place, Term


class PlaceAt:
    """Called on a term's class, the class of that term at a place (``Viscous.at(Place.X)(c)``); on an
    instance, the same term with its value(s) at that place (``Viscous(0.03).at(Place.X)``); a named error
    where the term cannot act there."""

    @overload
    def __get__(self, obj: None, owner: type[Term]) -> Callable[[Place], type[Term]]: ...

    @overload
    def __get__(self, obj: Term, owner: type[Term]) -> Callable[[Place], Term]: ...

    def __get__(
        self, obj: Optional[Term], owner: type[Term]
    ) -> Union[Callable[[Place], type[Term]], Callable[[Place], Term]]:
        if obj is None:
            return owner.class_at
        return obj.placed


__all__ = ["PlaceAt"]
