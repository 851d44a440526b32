"""The numeric engine: compiled (numba) solvers of one contact, plain floats and arrays in and out.

* ``codes``: the codes of the force families and the column order of the characteristics;
* ``forces``: the contact force of each family as a compiled function of (δ, δ̇);
* ``powerlaw``: the exact (quadrature) engine of F = K δ^n (1 + c δ̇): Hertz with Hunt–Crossley,
  Lankarani–Nikravesh and the other power-law damping laws;
* ``plastic``: the exact engine of elastic–plastic contact (Thornton's flattened spot, the bioyield
  element) on a half-space or a thin layer, and cardboard crushing; ``halfspace``: the same impact on a
  half-space walked in the speed (closed-form forces, no inversions: its fast path);
* ``adaptive``: adaptive Runge–Kutta with event location, for the laws with no first integral (Tsuji,
  Kuwabara–Kono, linear Kelvin–Voigt);
* ``rk4``: the founding paper's fixed-step RK4 (section 3), to reproduce its method;
* ``quadrature``: Gauss–Jacobi rules; ``checks``: physical checks of computed rows;
  ``moments``: streaming moments of a column;
* ``plasticforms``: Thornton's yield force and the Winkler layer in closed form (plain NumPy, no numba);
* ``jitcache``: numba's on-disk cache keyed on every file a compiled function may depend on.

No I/O, no units, no pandas, SciPy or plotting (an import-linter contract).
"""
