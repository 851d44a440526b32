"""Bruise onset, volume and geometry for a fruit impact (pure functions, SI, numpy arrays).

Three parts, each documented in docs/bruise.md:

* **Hertz subsurface stresses** on the axis of a circular Hertz contact (Johnson 1985, eq 3.45), the
  maximum shear stress τ_max/p0 and its depth z/a as functions of Poisson's ratio ν, and the peak
  pressure p0/Y at first yield (Tresca = von Mises on the axis).
* **Bruise-onset criteria** (``CRITERIA``): ``pressure`` (p0 ≥ σ_f), ``shear`` (τ_max ≥ σ_f/2) and
  ``energy`` (W ≥ W_th), each a ``BruiseCriterion`` whose ``margin`` is the compared quantity over its
  threshold, minus 1 (≥ 0: bruised).
* **Bruise volume and geometry**: the bruise-susceptibility model BV = BS (W − W_th)₊, the spherical-cap
  bruise BV = π d (3w² + 4d²)/24 and its inverse, and a bruise width from the contact width
  (Stropek & Gołacki 2020, pear).

Conventions: every function accepts floats or numpy arrays (broadcast together) and returns numpy
float64 scalars for scalar inputs. NaN inputs are treated as missing values and propagate to NaN
outputs (``is_bruised`` is False there); infinite or out-of-range inputs raise ``ValueError`` naming
the argument and the allowed range.

Sources: K. L. Johnson, *Contact Mechanics*, Cambridge University Press (1985), eq 3.45 and §11.4;
L. O. Opara & P. B. Pathare, Postharvest Biol. Technol. 91 (2014) 9–24 (bruise susceptibility);
Z. Stropek & K. Gołacki, Postharvest Biol. Technol. 163 (2020) 111120 (pear bruise vs contact geometry);
C. Thornton, J. Appl. Mech. 64 (1997) 383–386 and Thornton & Ning, Powder Technol. 99 (1998) 154–162
(yield-onset velocity of a sphere on a flat).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from fruitimpact.physics.constants import STANDARD_GRAVITY

#: Stropek & Gołacki (2020), pear, three highest impact speeds: contact width ≈ 1.4 × bruise width.
CONTACT_TO_BRUISE_WIDTH = 1.4

_POISSON_RANGE = (0.0, 0.5)
#: Above this ζ = z/a, 1 − ζ arctan(1/ζ) is summed as a series in 1/ζ² (the direct form cancels).
_SERIES_DEPTH = 4.0
#: 1 − arctan(x)/x = Σ_{k≥1} (−1)^(k+1) x^(2k)/(2k+1); 16 terms reach 1e-19 for x ≤ 1/4.
_SERIES = np.array([(-1.0) ** (k + 1) / (2 * k + 1) for k in range(1, 17)])


# --------------------------------------------------------------------------------------------- checks


def _values(name: str, value, low: float | None = None, high: float | None = None, *,
            low_open: bool = False, unit: str = "") -> np.ndarray:
    """``value`` as a float64 array; ValueError naming ``name`` if any value is infinite or outside
    [low, high] (``low_open``: (low, high]). NaN passes (a missing value)."""
    array = np.asarray(value, dtype=float)
    bad = np.isinf(array)
    if low is not None:
        bad |= (array <= low) if low_open else (array < low)
    if high is not None:
        bad |= array > high
    if bad.any():
        if low is not None and high is not None:
            allowed = f" in {'(' if low_open else '['}{low:g}, {high:g}]"
        elif low is not None:
            allowed = f" {'>' if low_open else '>='} {low:g}"
        else:
            allowed = ""
        count = int(np.count_nonzero(bad))
        first = array[bad].flat[0]
        extra = f" (the first of {count} values refused)" if count > 1 else ""
        suffix = f" [{unit}]" if unit else ""
        raise ValueError(f"{name} must be a finite number{allowed}{suffix}; got {float(first)!r}{extra}")
    return array


def _poisson(poisson) -> np.ndarray:
    return _values("poisson", poisson, *_POISSON_RANGE)


# ------------------------------------------------------------------------------ Hertz axis stresses


def _one_minus_z_arctan(zeta: np.ndarray) -> np.ndarray:
    """1 − ζ arctan(1/ζ) for ζ ≥ 0, accurate to rounding also for large ζ (series in x = 1/ζ)."""
    with np.errstate(divide="ignore", invalid="ignore"):
        direct = 1.0 - zeta * np.arctan2(1.0, zeta)
        x2 = 1.0 / np.square(np.maximum(zeta, _SERIES_DEPTH))
        series = x2 * np.polynomial.polynomial.polyval(x2, _SERIES)
    return np.where(zeta > _SERIES_DEPTH, series, direct)


def hertz_axis_stresses(depth_ratio, poisson):
    """Stresses on the axis of a Hertz circular contact, (σ_z/p0, σ_r/p0) [-] (compression < 0).

    Johnson (1985), *Contact Mechanics*, eq 3.45, with ζ = z/a:

        σ_z/p0 = −1/(1 + ζ²)
        σ_r/p0 = σ_θ/p0 = −(1 + ν)(1 − ζ arctan(1/ζ)) + 1/(2(1 + ζ²))

    Parameters
    ----------
    depth_ratio : float or array
        ζ = z/a [-], depth below the surface over the contact radius, finite and ≥ 0.
    poisson : float or array
        Poisson's ratio ν [-] of the body, in [0, 0.5].

    Returns
    -------
    sigma_z, sigma_r : tuple of float or array
        Axial and radial (= hoop) stress over the peak pressure p0 [-], broadcast shape.
    """
    zeta, nu = np.broadcast_arrays(_values("depth_ratio", depth_ratio, 0.0), _poisson(poisson))
    inverse = 1.0 / (1.0 + np.square(zeta))
    sigma_z = -inverse
    sigma_r = -(1.0 + nu) * _one_minus_z_arctan(zeta) + 0.5 * inverse
    return sigma_z[()], sigma_r[()]


def _shear_slope(zeta: np.ndarray, nu: np.ndarray):
    """d/dζ and d²/dζ² of f = (σ_r − σ_z)/p0 = −(1+ν)(1 − ζ arctan(1/ζ)) + 3/(2(1+ζ²)) (= 2τ/p0)."""
    inverse = 1.0 / (1.0 + np.square(zeta))
    slope = (1.0 + nu) * (np.arctan2(1.0, zeta) - zeta * inverse) - 3.0 * zeta * np.square(inverse)
    curvature = -2.0 * (1.0 + nu) * np.square(inverse) - 3.0 * (1.0 - 3.0 * np.square(zeta)) * inverse ** 3
    return slope, curvature


def _max_shear_depth(nu: np.ndarray) -> np.ndarray:
    """ζ* maximising τ(ζ) on the axis, for each finite ν in [0, 0.5] (1-D array): root of df/dζ by a
    safeguarded Newton iteration (bisection where a Newton step leaves the bracket), each entry until
    its relative step is ≤ 1e-14 (then ζ is within about 1e-16 of the root: quadratic convergence).

    df/dζ = (1+ν) A(ζ) − B(ζ) with A = arctan(1/ζ) − ζ/(1+ζ²) > 0 and B = 3ζ/(1+ζ²)² is linear in ν, so
    its sign at ζ = 0.05 (> 0) and ζ = 2 (< 0), checked at ν = 0 and 0.5, holds for every ν between:
    [0.05, 2] brackets the root. d²f/dζ² < 0 for ζ < 1/√3, which holds at the root (≤ 0.548), so the
    root is a maximum and Newton converges quadratically once close."""
    low = np.full_like(nu, 0.05)
    high = np.full_like(nu, 2.0)
    zeta = 0.382 + 0.332 * nu  # straight line through the ν = 0 and 0.5 roots: start within 0.01
    active = np.arange(nu.size)  # a converged entry is left alone: each ν gets the same bits in any batch
    for _ in range(100):
        z, n, lo, hi = zeta[active], nu[active], low[active], high[active]
        slope, curvature = _shear_slope(z, n)
        above = slope > 0.0  # the root lies above ζ
        lo = np.where(above, z, lo)
        hi = np.where(above, hi, z)
        newton = z - slope / curvature
        inside = (newton >= lo) & (newton <= hi)  # inclusive: a step lost to rounding is convergence
        new = np.where(inside, newton, 0.5 * (lo + hi))
        zeta[active], low[active], high[active] = new, lo, hi
        active = active[np.abs(new - z) > 1e-14 * new]
        if active.size == 0:
            return zeta
    raise RuntimeError("hertz_max_shear: the depth of the maximum shear did not converge")  # pragma: no cover


def hertz_max_shear(poisson):
    """Maximum shear stress under a Hertz circular contact and its depth, (τ_max/p0, z/a) [-].

    τ = ½|σ_z − σ_r| on the axis (Johnson 1985, eq 3.45; ``hertz_axis_stresses``) maximised over
    ζ = z/a ≥ 0 by a safeguarded Newton iteration on the analytic derivative (ζ to about 1e-15). The
    maximum over the whole body lies on the axis (an off-axis scan in the background note; docs/bruise.md). Computed once per distinct ν, so an
    array of 10⁶ rows with a few distinct values costs little more than ``np.unique``.

    For ν = 0.3: 0.3100 p0 at z = 0.481 a (Johnson quotes 0.31 p0 at about 0.48 a).

    Parameters
    ----------
    poisson : float or array
        Poisson's ratio ν [-] of the fruit flesh, in [0, 0.5] (ValueError outside).

    Returns
    -------
    shear_ratio, depth_ratio : tuple of float or array
        τ_max/p0 [-] and the depth of the maximum z/a [-], each shaped like ``poisson``.
    """
    nu = _poisson(poisson)
    distinct, inverse = np.unique(nu.ravel(), return_inverse=True)
    shear = np.full_like(distinct, np.nan)
    depth = np.full_like(distinct, np.nan)
    known = [float(v) in _MAX_SHEAR for v in distinct]
    for i in np.flatnonzero(known):
        shear[i], depth[i] = _MAX_SHEAR[float(distinct[i])]
    todo = ~np.asarray(known, dtype=bool) & ~np.isnan(distinct)
    if todo.any():
        # a value of ν always gets the same bits (each is iterated alone), so cached and fresh values agree
        depth[todo] = _max_shear_depth(distinct[todo])
        sigma_z, sigma_r = hertz_axis_stresses(depth[todo], distinct[todo])
        shear[todo] = 0.5 * np.abs(sigma_z - sigma_r)
        if len(_MAX_SHEAR) + int(todo.sum()) > _MAX_SHEAR_SIZE:
            _MAX_SHEAR.clear()
        for i in np.flatnonzero(todo)[:_MAX_SHEAR_SIZE]:
            _MAX_SHEAR[float(distinct[i])] = (float(shear[i]), float(depth[i]))
    return shear[inverse].reshape(nu.shape)[()], depth[inverse].reshape(nu.shape)[()]


#: τ_max/p0 and z/a by value of ν, computed once (a simulate() call, a drop or a line point has one or a few
#: values of ν; the root search took a third of one simulate()).  Bounded: cleared when full.
_MAX_SHEAR: dict[float, tuple[float, float]] = {}
_MAX_SHEAR_SIZE = 4096


def shear_onset_pressure_factor(poisson):
    """Peak Hertz pressure at first yield over the yield stress, p0/Y = 1/(2 τ_max/p0) [-].

    Tresca: yield where τ_max = Y/2. On the axis σ_r = σ_θ, so von Mises gives the same onset
    (Johnson 1985, §6.2; the note's table: 1.613 for ν = 0.3, Johnson quotes 1.60).

    Parameters
    ----------
    poisson : float or array
        Poisson's ratio ν [-], in [0, 0.5].
    """
    shear, _ = hertz_max_shear(poisson)
    return 0.5 / shear


def max_shear_stress(peak_pressure, poisson):
    """Maximum subsurface shear stress τ_max = (τ_max/p0)(ν) · p0 [Pa] under a Hertz contact.

    Parameters
    ----------
    peak_pressure : float or array
        Peak (centre) Hertz contact pressure p0 [Pa], ≥ 0.
    poisson : float or array
        Poisson's ratio ν [-], in [0, 0.5].
    """
    pressure = _values("peak_pressure", peak_pressure, 0.0, unit="Pa")
    shear, _ = hertz_max_shear(poisson)
    return (shear * pressure)[()]


# ------------------------------------------------------------------------------------------ criteria


def _pressure_ratio(*, peak_pressure, failure_stress):
    pressure = _values("peak_pressure", peak_pressure, 0.0, unit="Pa")
    stress = _values("failure_stress", failure_stress, 0.0, low_open=True, unit="Pa")
    return pressure / stress


def _shear_ratio(*, peak_pressure, poisson, failure_stress):
    stress = _values("failure_stress", failure_stress, 0.0, low_open=True, unit="Pa")
    return max_shear_stress(peak_pressure, poisson) / (0.5 * stress)


def _energy_ratio(*, absorbed_energy, threshold_energy):
    energy = _values("absorbed_energy", absorbed_energy, unit="J")
    threshold = _values("threshold_energy", threshold_energy, 0.0, low_open=True, unit="J")
    return energy / threshold


_INPUTS = ("peak_pressure", "poisson", "absorbed_energy", "failure_stress", "threshold_energy")


@dataclass(frozen=True)
class BruiseCriterion:
    """A bruise-onset criterion: bruised where ``quantity`` ≥ ``threshold``.

    Attributes
    ----------
    name : str
        Registry key (``CRITERIA``).
    description : str
        One line: what is compared with what.
    quantity : str
        The quantity compared, with its unit.
    threshold : str
        The threshold it is compared with, with its unit.
    reference : str
        Where the criterion comes from.
    inputs : tuple of str
        The keyword arguments of ``margin`` that this criterion uses (the others are ignored).
    ratio : callable
        ``ratio(**{name: array for name in inputs})`` → quantity / threshold [-].
    """

    name: str
    description: str
    quantity: str
    threshold: str
    reference: str
    inputs: tuple[str, ...]
    ratio: Callable[..., np.ndarray]

    def margin(self, *, peak_pressure=None, poisson=None, absorbed_energy=None, failure_stress=None,
               threshold_energy=None):
        """Dimensionless margin quantity/threshold − 1 [-]: ≥ 0 means bruised (NaN where an input is NaN).

        Only the criterion's own ``inputs`` are needed; ValueError if one of them is missing.

        Parameters
        ----------
        peak_pressure : float or array
            Peak Hertz contact pressure p0 [Pa], ≥ 0.
        poisson : float or array
            Poisson's ratio ν of the flesh [-], in [0, 0.5].
        absorbed_energy : float or array
            Energy absorbed by the fruit W [J] (finite; ≤ 0 counts as none).
        failure_stress : float or array
            Flesh failure (bioyield) stress σ_f [Pa], > 0.
        threshold_energy : float or array
            Bruise threshold energy W_th [J], > 0.
        """
        given = dict(zip(_INPUTS, (peak_pressure, poisson, absorbed_energy, failure_stress, threshold_energy)))
        missing = [name for name in self.inputs if given[name] is None]
        if missing:
            raise ValueError(f"bruise criterion {self.name!r} needs {', '.join(missing)}")
        ratio = np.asarray(self.ratio(**{name: given[name] for name in self.inputs}))
        return (ratio - 1.0)[()]


CRITERIA: dict[str, BruiseCriterion] = {
    criterion.name: criterion
    for criterion in (
        BruiseCriterion(
            name="pressure",
            description="bruised when the peak Hertz contact pressure reaches the flesh failure stress, p0 ≥ σ_f",
            quantity="peak contact pressure p0 [Pa]",
            threshold="flesh failure stress σ_f [Pa]",
            reference="Thornton (1997) with p_y = σ_f; damage-and-surfaces note §a.6 criterion (i)",
            inputs=("peak_pressure", "failure_stress"),
            ratio=_pressure_ratio,
        ),
        BruiseCriterion(
            name="shear",
            description="bruised when the maximum subsurface shear reaches half the flesh failure stress, "
                        "τ_max ≥ σ_f/2 (Tresca with Y = σ_f), i.e. p0 ≥ σ_f/(2 τ_max/p0(ν))",
            quantity="maximum subsurface shear stress τ_max [Pa]",
            threshold="half the flesh failure stress σ_f/2 [Pa]",
            reference="Johnson (1985), Contact Mechanics, eq 3.45 and §6.2; note §a.6 criterion (ii)",
            inputs=("peak_pressure", "poisson", "failure_stress"),
            ratio=_shear_ratio,
        ),
        BruiseCriterion(
            name="energy",
            description="bruised when the energy absorbed by the fruit reaches a threshold energy, W ≥ W_th",
            quantity="absorbed energy W [J]",
            threshold="bruise threshold energy W_th [J]",
            reference="Opara & Pathare (2014), Postharvest Biol. Technol. 91:9–24 (BV = BS (E − E_th)₊)",
            inputs=("absorbed_energy", "threshold_energy"),
            ratio=_energy_ratio,
        ),
    )
}


def _criterion(criterion) -> BruiseCriterion:
    if isinstance(criterion, BruiseCriterion):
        return criterion
    try:
        return CRITERIA[criterion]
    except (KeyError, TypeError):
        raise ValueError(f"criterion must be one of {', '.join(CRITERIA)}; got {criterion!r}") from None


def bruise_margin(criterion, *, peak_pressure=None, poisson=None, absorbed_energy=None, failure_stress=None,
                  threshold_energy=None):
    """Bruise margin of ``criterion`` (a name of ``CRITERIA`` or a ``BruiseCriterion``) [-].

    The compared quantity over its threshold, minus 1: p0/σ_f − 1 (``pressure``),
    τ_max/(σ_f/2) − 1 (``shear``), W/W_th − 1 (``energy``). ≥ 0 means bruised. Only the inputs the
    criterion uses are needed (``CRITERIA[name].inputs``); arrays broadcast; NaN propagates.
    See ``BruiseCriterion.margin`` for the units.
    """
    return _criterion(criterion).margin(
        peak_pressure=peak_pressure, poisson=poisson, absorbed_energy=absorbed_energy,
        failure_stress=failure_stress, threshold_energy=threshold_energy)


def is_bruised(criterion, *, peak_pressure=None, poisson=None, absorbed_energy=None, failure_stress=None,
               threshold_energy=None):
    """``bruise_margin(...) >= 0`` (bool or bool array): bruised at and above the threshold.
    False where the margin is NaN (a NaN input): check ``bruise_margin`` to tell those rows apart."""
    margin = bruise_margin(
        criterion, peak_pressure=peak_pressure, poisson=poisson, absorbed_energy=absorbed_energy,
        failure_stress=failure_stress, threshold_energy=threshold_energy)
    return np.greater_equal(margin, 0.0)


# ---------------------------------------------------------------------------- bruise volume, geometry


def bruise_volume(absorbed_energy, susceptibility, threshold_energy=0.0, bruised=None):
    """Bruise volume BV = BS (W − W_th)₊ [m³] (Opara & Pathare 2014; note §b.1).

    Parameters
    ----------
    absorbed_energy : float or array
        Energy W [J] absorbed by the fruit in the impact: for a drop on a rigid surface the caller
        passes ½ m V² (1 − e²), the fruit's share of it on a compliant surface. Finite; values ≤ W_th
        give no bruise (so rounding below 0 at e = 1 is harmless).
    susceptibility : float or array
        Bruise susceptibility BS [m³/J], ≥ 0 (3 cm³/J = 3e-6 m³/J).
    threshold_energy : float or array
        Threshold energy W_th [J], ≥ 0 (default 0).
    bruised : bool or bool array, optional
        Onset mask (e.g. ``is_bruised``): the volume is 0 where it is False.
    """
    energy = _values("absorbed_energy", absorbed_energy, unit="J")
    susceptibility = _values("susceptibility", susceptibility, 0.0, unit="m³/J")
    threshold = _values("threshold_energy", threshold_energy, 0.0, unit="J")
    volume = susceptibility * np.maximum(energy - threshold, 0.0)
    if bruised is not None:
        volume = np.where(np.asarray(bruised, dtype=bool), volume, 0.0)
    return volume[()]


def cap_volume(depth, width):
    """Volume of a spherical-cap bruise, BV = π d (3w² + 4d²)/24 = π d (3b² + d²)/6 with b = w/2 [m³].

    Parameters
    ----------
    depth : float or array
        Bruise depth d [m] below the surface, ≥ 0.
    width : float or array
        Bruise width w [m] (chord at the surface), ≥ 0.

    References
    ----------
    Spherical-cap geometry; used for bruises by Mohsenin (1986) and Holt & Schoorl (1977) (attribution as
    reported in the postharvest literature; note §b.2).
    """
    d = _values("depth", depth, 0.0, unit="m")
    w = _values("width", width, 0.0, unit="m")
    return (math.pi * d * (3.0 * np.square(w) + 4.0 * np.square(d)) / 24.0)[()]


def cap_depth(volume, width):
    """Depth d [m] of the spherical cap of width ``width`` holding ``volume``: the inverse of ``cap_volume``.

    With s = d/w and q = 6 V/(π w³), the cap formula is s³ + (3/4) s = q: one real root, increasing
    in q, s = sinh(arsinh(4q)/3) (the hyperbolic form of Cardano's solution, accurate for all q ≥ 0),
    polished by one Newton step (relative error about 1e-16). Where w = 0 or q > 1e30 the cap is
    a sphere to rounding, d = (6V/π)^(1/3). Volume 0 gives depth 0.

    Parameters
    ----------
    volume : float or array
        Bruise volume V [m³], ≥ 0.
    width : float or array
        Bruise width w [m], ≥ 0.
    """
    v = _values("volume", volume, 0.0, unit="m³")
    w = _values("width", width, 0.0, unit="m")
    v, w = np.broadcast_arrays(v, w)
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        q = (6.0 / math.pi) * v / (w * w * w)
        sphere = (w == 0.0) | (q > 1e30)  # w = 0 gives q = inf or 0/0; NaN goes on and stays NaN
        if sphere.any():
            q = np.where(sphere, 0.0, q)
        s = np.sinh(np.arcsinh(4.0 * q) / 3.0)
        s -= (s * (s * s + 0.75) - q) / (3.0 * s * s + 0.75)
        depth = np.asarray(s * w)
        if sphere.any():
            depth[sphere] = np.cbrt((6.0 / math.pi) * v[sphere])
    return depth[()]


def bruise_geometry(volume, contact_radius, width_ratio=CONTACT_TO_BRUISE_WIDTH):
    """Bruise depth and width [m] from the bruise volume and the peak contact radius.

    width = 2 a / ``width_ratio``, the ratio of the contact width to the bruise width it leaves, measured per
    fruit (pear: 1.4 at the three highest impact speeds of Stropek & Gołacki 2020, Postharvest Biol. Technol.
    163:111120; the library holds it per fruit and no fruit borrows another's: NaN gives an unknown width
    and depth).  depth: the spherical cap of that width holding the volume (``cap_depth``).  Zero volume
    gives zero depth and width.

    Parameters
    ----------
    volume : float or array
        Bruise volume [m³], ≥ 0 (e.g. ``bruise_volume``).
    contact_radius : float or array
        Peak Hertz contact radius a [m], ≥ 0.
    width_ratio : float or array
        Contact width / bruise width [-], > 0, or NaN (unknown).

    Returns
    -------
    depth, width : tuple of float or array [m]
    """
    v = _values("volume", volume, 0.0, unit="m³")
    a = _values("contact_radius", contact_radius, 0.0, unit="m")
    ratio = np.asarray(width_ratio, dtype=float)
    v, a, ratio = np.broadcast_arrays(v, a, ratio)
    with np.errstate(invalid="ignore", divide="ignore"):
        width = np.where(v == 0.0, 0.0, np.where(np.isnan(v), np.nan, 2.0 * a / ratio))
    return cap_depth(v, width), width[()]


# ------------------------------------------------------------------------------------- onset height


def onset_drop_height_rigid(failure_stress_equivalent_pressure, density, contact_modulus, g=STANDARD_GRAVITY):
    """Drop height [m] at which an elastic Hertz impact of a homogeneous sphere on a rigid flat first
    reaches the peak pressure p: h = π⁴ p⁵/(80 g ρ E*⁴).

    From ½ m V² = (2/5) F δ at the peak (Hertz, F = (4/3) E* √R δ^(3/2)), p0 = 2 E* a/(π R), a² = R δ and
    m = (4/3) π R³ ρ; R cancels, so the height does not depend on fruit size (Thornton 1997;
    Johnson 1985 §11.4; note §a.2). Pass p = σ_f for the ``pressure`` criterion and
    p = σ_f · ``shear_onset_pressure_factor(ν)`` for ``shear``.

    Parameters
    ----------
    failure_stress_equivalent_pressure : float or array
        Peak Hertz pressure at onset p [Pa], ≥ 0.
    density : float or array
        Fruit density ρ [kg/m³], > 0.
    contact_modulus : float or array
        Contact modulus E* [Pa], > 0 (E/(1 − ν²) on a rigid surface).
    g : float or array
        Gravitational acceleration [m/s²], > 0 (default: standard gravity 9.80665, ``fruitimpact.physics.constants``).
    """
    p = _values("failure_stress_equivalent_pressure", failure_stress_equivalent_pressure, 0.0, unit="Pa")
    rho = _values("density", density, 0.0, low_open=True, unit="kg/m³")
    modulus = _values("contact_modulus", contact_modulus, 0.0, low_open=True, unit="Pa")
    gravity = _values("g", g, 0.0, low_open=True, unit="m/s²")
    return (math.pi ** 4 * p * (p / modulus) ** 4 / (80.0 * gravity * rho))[()]


__all__ = [
    "CONTACT_TO_BRUISE_WIDTH", "CRITERIA", "BruiseCriterion", "bruise_geometry",
    "bruise_margin", "bruise_volume", "cap_depth", "cap_volume", "hertz_axis_stresses", "hertz_max_shear",
    "is_bruised", "max_shear_stress", "onset_drop_height_rigid", "shear_onset_pressure_factor",
]
