"""The founding paper reproduced, and comparisons between models.

* ``paper``: Table 1 and the figures of "Theoretical aspects about simulating the reaction to impact of
  apples on rigid plane surfaces" (``data/table1.csv``), recomputed and compared;
* ``comparison``: the damping laws side by side on one impact.
"""
