"""Is a contact a new fruit or the rebound of an earlier one?  Decided by the fruit's own physics
(issue 13, item 1), never by "smaller and soon".

A fruit that leaves the plate at V₂ flies 2 V₂/g (no drag) and lands again as the *same* fruit: the
same mass m, contact stiffness K and damping, at the lower speed.  For the force law F = K δ^1.5 (1 + c δ̇) of
the simulator every characteristic is a Hertz scale times a function of x = c V alone (``engine.powerlaw``;
δ_H = (1.25 m V²/K)^0.4, t_H = δ_H/V):

    F_max = K δ_H^1.5 · P(x)/1.25,   t_c = t_H · τ_c(x),   T = t_H · τ_T(x),   ∫F dt = m V (1 + e(x)),

with P, τ_c, τ_T, e the dimensionless peak, time to peak, duration and restitution of the exact engine
(m = V = 1, K = 1.25).  So if a contact j is the rebound of contact p at the speed ratio r = V_j/V_p:

    x_j = r^β x_p,
    F_j / F_p  = r^1.2  · P(x_j)/P(x_p),
    t_cj/t_cp  = r^-0.2 · τ_c(x_j)/τ_c(x_p),
    I_j / I_p  = r · (1 + e(x_j))/(1 + e(x_p)),

none of which needs m, K or V.  β says how the damping follows the speed, and it is not settled for fruit:
β = 1 when c is a material constant (Hunt–Crossley: a slower impact is livelier), β = 0 when the restitution
is (Lankarani–Nikravesh 1990, Flores et al. 2011: c ∝ 1/V), both named by the founding paper.  The tests take
x_j anywhere in that range (``DAMPING_EXPONENT``), nearest the contact's own measured x (``rebound_x``), until
the line's rebounds have shown its own (``PulseSummary.damping_exponent``, read by the analysis): on lines built
with a constant restitution, x_j = r x_p alone took 268 of their rebounds for new fruit in six recordings.

The impulse ratio gives r (it does not depend on where the fruit lands on itself); the peak force, the
time to peak and the shape x must then agree with it, r must be the restitution of p (r ≈ e_p: the fruit
cannot come back faster, and spin or an off-axis bounce take a little), and, when p's impact speed is known
(the line's drop height, or a fitted velocity), the observed flight from p's separation to j's onset must be the
predicted 2 r V_p/g.

Each test gives a deviation in units of its tolerance; the score S of the hypothesis is the largest.
Tolerances (``TOLERANCES``), each drawn from what the physics leaves uncertain:

* flight: ±25 % (a spinning or off-axis fruit's flight is off by ±10–20 %; the estimate of r adds its
  own error in quadrature);
* speed ratio r against e_p: −25 % / +10 % (energy lost to spin and tangential motion lowers the
  vertical rebound speed, nothing raises it: a fruit cannot come back faster than it left; e_p itself
  is uncertain: 3 × its relative standard error is added in quadrature);
* peak force and time to peak: 3 × √(σ_meas² + 4 %²), the 4 % for a rebound landing on another spot
  of the fruit (local radius and modulus ±10 % move F_max and t_c by ~4 %: both go as K^±0.4);
* shape: the measured x_j against the nearest x the damping laws allow (``rebound_x``), within
  3 × √(σ_j² + (x_j/x_p · σ_p)² + (0.1 x_j)²): 0 inside the range;
* energy: I_j/I_p ≤ 1 within 3 × the impulses' error (a rebound carries at most 2 e_p/(1 + e_p) < 1 of its
  parent's impulse), beyond it no rebound whatever the other tests say.

S ≤ 1: a rebound.  S > 1: a new fruit.  Near the boundary (``AMBIGUOUS`` band) the decision is kept but
flagged ambiguous, with the evidence (predicted and observed flight and peak).  A known feed
(``pitch``) is a prior: a contact on the pitch grid of the lane's last fruit needs S ≤ 0.8 to be a
rebound, one far off the grid S ≤ 1.25; without it the rule above alone decides.

The peak, time to peak and impulse are the raw indices (``from_indices``), the same with or without
``--fit``, so the decision is too; the fit then splits the Hertz scales at the rebound's speed r V_p.
The raw shape x is read from h = ∫F dt / (F_max t_c), which for the force law is (1 + e(x))/(P(x) τ_c(x)), a
function of x alone, increasing up to x ≈ 2.6 (e ≈ 0.35) and flat near its top, so the raw x is weak
for e ≈ 0.35–0.5 (its uncertainty is propagated).  So where a shape fit of the contact converged (the
simulator's pulse fitted to its own samples, e ± 0.01 at 1 % noise; ``analysis`` fits every contact,
with or without ``--fit``) its x, e and separation time replace the raw ones (``refine``).

A rebound is judged when it lands, against the contacts still free; where that fails, two second readings
(``measured``): the pairing that explains it and the contact that had claimed its parent, each by the tests above
(``reassigned``: each contact rebounds once), and its parent read as a fruit alone where a due rebound may have
landed with it too closely to tell apart (``held_alternative``).

The package, one module per job: ``pulses`` (what the tests know of a contact, the force law's tables, the
verdict), ``measured`` (a contact against earlier measured or predicted contacts), ``lane`` (a contact against the
lane's measured fruit, standing for a fruit that was not measured).
"""

from fruitimpact.signals.rebounds.lane import (CHI2_3_99, CHI2_4_99, FLIGHT_TOLERANCE_SD, HIDDEN_FRUIT_MIN,
                                               HIDDEN_SCORE_MAX, LANE_FRUIT_MIN, LOT_IMPULSE_SD, LOT_STIFFNESS_SD,
                                               NEW_FRUIT_EXCLUDED, ORPHAN_MARGIN, PAIR_DISTANCE_MAX, PAIR_MARGIN,
                                               SLOW_PARENT_RATIO, LaneFruit, impulse_distance, judge_unmeasured,
                                               landed_with_rebound, lane_fruit, median_of, rebound_of_a_rebound,
                                               rebounds_landed_together, robust_sd, too_light_for_fruit,
                                               unmeasured_fruit)
from fruitimpact.signals.rebounds.measured import (EXPECTED_RATIO, EXPECTED_RATIO_SD, HELD_FRUIT_SHARE,
                                                   LOT_RESTITUTION_SD, QUIET_LANE_FRUIT, claimed_parent,
                                                   expected_rebound, held_alternative, hidden_rebound, judge,
                                                   likeliest_hidden, reassigned, rebound_pulse, rebounds_due,
                                                   without_held)
from fruitimpact.signals.rebounds.pulses import (AMBIGUOUS, DAMPING_EXPONENT, NEW_FRUIT, RAW_SD, TOLERANCES,
                                                 PulseSummary, Verdict, flight_time, from_indices, landing_speed,
                                                 rebound_x, refine, shape_table)

__all__ = ["AMBIGUOUS", "CHI2_3_99", "CHI2_4_99", "DAMPING_EXPONENT", "EXPECTED_RATIO", "EXPECTED_RATIO_SD",
           "FLIGHT_TOLERANCE_SD", "HELD_FRUIT_SHARE", "HIDDEN_FRUIT_MIN", "HIDDEN_SCORE_MAX", "LANE_FRUIT_MIN",
           "LOT_IMPULSE_SD", "LOT_RESTITUTION_SD", "LOT_STIFFNESS_SD", "LaneFruit", "NEW_FRUIT", "NEW_FRUIT_EXCLUDED",
           "ORPHAN_MARGIN", "PAIR_DISTANCE_MAX", "PAIR_MARGIN", "PulseSummary", "QUIET_LANE_FRUIT", "RAW_SD",
           "SLOW_PARENT_RATIO", "TOLERANCES", "Verdict", "claimed_parent", "expected_rebound", "flight_time",
           "from_indices", "held_alternative", "hidden_rebound", "impulse_distance", "judge", "judge_unmeasured",
           "landed_with_rebound", "landing_speed", "lane_fruit", "likeliest_hidden", "median_of", "reassigned",
           "rebound_of_a_rebound", "rebound_pulse", "rebound_x", "rebounds_due", "rebounds_landed_together", "refine",
           "robust_sd", "shape_table", "too_light_for_fruit", "unmeasured_fruit", "without_held"]
