"""Fruit handling: what a drop, a transfer point or a whole line does to a fruit or a lot.

* ``drops``: one drop with all its bounces (:func:`drop`);
* ``heights``: the safe drop height onto a surface (:func:`safe_height`);
* ``line``: the bruise audit of a line of transfer points over a lot (:func:`audit_line`);
* ``droptests``: bruise threshold, susceptibility and failure stress fitted to drop or pendulum tests
  (:func:`fit_damage`), the fitted fruit written as a fruit file.

The bruise criteria themselves are in :mod:`fruitimpact.damage`; the impacts come from
:mod:`fruitimpact.impact.evaluation`.
"""
