"""The distortion term's law failing alone is the drive's harmonics through a G not measured there.

The ``distortion`` term carries each input's own harmonics through G at their frequencies, with G
interpolated between the tested frequencies and extended beyond them (fitting.carry_waveforms); its scale
lam is one value for all experiments. On a resonant G (review 35's null_h3r: wn 6, Q 5, delay 0.03, tested
at 1-7 rad/s, a 3 % third harmonic in the drive of a plain plant) G at 6 rad/s (between 5 and 7) and at
10.5-21 rad/s (above) is not that G, lam differs between experiments (p = 7.9e-187) and the verdict said the
term "stands in for physics outside the library". When it is the only term whose law failed, :func:`text`
says what it is: the drive's harmonics through a G the band does not pin down.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Optional

from ..terms import Distortion


def text(failed: Mapping[str, float]) -> Optional[str]:
    """The clause when the distortion term is the only one whose law failed (None otherwise)."""
    if set(failed) != {Distortion.kind}:
        return None
    p = failed[Distortion.kind]
    return (
        f"; not named: {Distortion.label} (p = {p:.2g}): its scale, one value for all experiments, fails "
        "(its law): G at the input's harmonics is not the G it carries there (a low-order model of the "
        "tested points, or interpolated between them and extended beyond; a resonance bends it), so the "
        "residual can be the drive's own harmonics through a G these experiments do not measure rather "
        "than physics outside the library; G measured at the harmonics' frequencies, or a clean sine, "
        "would tell"
    )
