"""A parametric, stable, proper ``G(s)`` fitted to the identified frequency-response points (issue #11).

The identification gives ``G(j omega_i) = |G_i| exp(-j phi_i)`` at the tested frequencies, each with the
2x2 covariance of ``(|G_i|, phi_i)``.  :func:`fit_transfer_function` turns them into a rational transfer
function with an optional pure delay,

    G(s) = exp(-tau s) (b_0 s^m + ... + b_m) / (s^n + a_1 s^(n-1) + ... + a_n),   m <= n <= 4,

in three steps:

1. **Start** (Sanathanan-Koerner): the linearised, re-weighted least squares
   ``min sum_i |w_i (N(s_i) - G_i D(s_i)) / D_(k-1)(s_i)|^2`` iterated a few times, for a few trial delays
   between 0 and the delay the high-frequency phase slope suggests; unstable poles of the start are
   reflected into the left half plane (``p -> -conj p``, which keeps ``|D(j omega)|``) and the numerator
   re-solved.  C. K. Sanathanan and J. Koerner, *Transfer function synthesis as a ratio of two complex
   polynomials*, IEEE Trans. Automatic Control 8 (1963) 56-58.
2. **Refinement**: covariance-weighted nonlinear least squares (``scipy.optimize.least_squares``) on the
   whitened complex residuals ``L_i^-1 [Re, Im](G(j omega_i) - G_i)``, ``L_i L_i^T`` the covariance of
   ``(Re G_i, Im G_i)`` mapped from that of ``(|G_i|, phi_i)`` by the delta method.  Stability is
   enforced by the parameterisation: the denominator is a product of sections ``s^2 + e^p s + e^q`` and
   (odd n) ``s + e^r``, each Hurwitz for every real ``p, q, r``; the delay is bounded below by 0.
3. **Order selection** over ``0 <= m <= n <= max_order`` (and with/without delay) by AICc (default) or
   BIC on the weighted chi-square; the table of every candidate is kept on the result.

The parameter covariance is the inverse Gauss-Newton information of the whitened residuals (scaled by the
residual variance when the points carry no uncertainty), and :meth:`TransferFunctionFit.predict` carries
it to untested frequencies by the delta method.

The points are those of the alpha-normalised model, so the fitted transfer function is ``alpha G``.

Modules: ``_points`` (the points and their whitening), ``_model`` (the Hurwitz parameterisation),
``_refine`` (one candidate fitted), ``_select`` (the order chosen and why), ``_fit`` (the entry point and
the result's uncertainty), ``_result`` (the result types).
"""

from __future__ import annotations

from ._fit import MAX_ORDER, fit_transfer_function
from ._result import FrequencyPrediction, OrderCandidate, TransferFunctionFit

__all__ = [
    "fit_transfer_function",
    "TransferFunctionFit",
    "FrequencyPrediction",
    "OrderCandidate",
    "MAX_ORDER",
]
