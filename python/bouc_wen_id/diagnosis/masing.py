"""The verdict's word when a spring across the hysteretic element (on x) is named from saturating loops.

A Prandtl-Ishlinskii operator on x (a weighted sum of play operators) is a spring in parallel with a
distribution of stops: ``sum_i w_i play_ri(x) = (sum_i w_i) x - sum_i w_i stop_ri(x)``. Its loop is a
Masing loop (each branch is the initial loading curve scaled by 2, and depends only on the travel since
the reversal). When every experiment reverses from saturation, Bouc-Wen's branches are one curve of the
travel too (they all start from the saturated state), and a distribution of stops can draw any such
curve: the steady loops cannot tell "Bouc-Wen + a spring on x" from "Bouc-Wen + a Prandtl-Ishlinskii loop
on x" (or a Masing-type element in place of Bouc-Wen's).

Measured (benches/blind.py's six Prandtl-Ishlinskii cases, the same plants, designs and noise with the
effect re-sized, its RMS over the averaged noise sd): at 10x and 30x all six "explained by: parallel
stiffness on x" with a final model that passes; at 100x three still named it with a passing final model
(p 0.06-1), two "explained in part", one "unexplained"; at 300x all six "unexplained". A PI loop written
here in NumPy through a first-order or a resonant G with a delay (tests/test_diagnosis_masing.py) is
named the same way at 20x (final p 0.91, 0.89). So at such sizes no shape test of the residual can
separate them, and the verdict says so instead (:func:`masing_text`) - only when every experiment
saturates, as :func:`caveats.play_text` does for play and an output backlash: with an experiment
below saturation, a
Masing branch from a lower reversal is its initial curve scaled by 2 while Bouc-Wen's is not, so the
separating experiment has been run and the law and adequacy tests speak for themselves. Their power
there is limited: the NumPy PI loop with an experiment at 0.3 of saturation added was still named a
spring on x at 30x (final p 0.09, no clause), and refused by the spring's law only at 100x.
"""

from __future__ import annotations

from collections.abc import Sequence

from ..terms import StiffnessX
from .result import NamedTerm

#: The words that mark the Masing caveat in a verdict (benches read them).
MASING_MARK = "a loop of another family"


def masing_text(named: Sequence[NamedTerm], saturated: bool) -> str:
    """The clause after a verdict naming a spring on x when ``saturated`` (every experiment's latent
    amplitude at or past the saturation level, :func:`caveats.latent_levels`); empty otherwise."""
    if not saturated or not any(t.term == StiffnessX.kind for t in named):
        return ""
    label = StiffnessX.place_label()
    return (
        f"; {label} may be the elastic part of {MASING_MARK}: a Prandtl-Ishlinskii operator on x (a spring "
        "in parallel with a distribution of stops, a Masing-type loop) draws the same steady loops when "
        "every reversal starts from saturation, as here; what separates them is experiments at amplitudes "
        "from well below saturation to past it, and minor loops (a Masing branch is the initial loading "
        "curve scaled by 2 and returns to the reversal it left; Bouc-Wen's is not, in general), with the "
        "loop well above the noise (measured: such a loop at 10-30x the averaged noise sd fits as this "
        "spring; one below-saturation amplitude added, the spring's law refused it at 100x)"
    )
