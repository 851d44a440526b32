"""Fruit damage (bruising): Hertz subsurface stresses, bruise-onset criteria, and bruise volume and
geometry (``fruitimpact.damage.bruise``; background in docs/bruise.md); the bruise model's maximum-likelihood fit to
drop or pendulum tests (``fruitimpact.damage.fitting``). Pure numerics: numpy and math only."""
