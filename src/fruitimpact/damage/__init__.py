"""Fruit damage (bruising): Hertz subsurface stresses, bruise-onset criteria, and bruise volume and
geometry (``fruitimpact.damage.bruise``; background in docs/bruise.md). Pure numerics: numpy and math only."""
