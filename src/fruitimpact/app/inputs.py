"""A page's request read as the CLI reads its options: names checked, values as the user typed them.

Every page sends a JSON object of inputs by name; a value is a number or a text with its unit (``"30cm"``), an
empty text or null means "not given", a flag is a JSON true or false.  Unknown names are refused, as the CLI
refuses an unknown option, with the input named so that the page shows the refusal next to its control.
"""

from __future__ import annotations

from fruitimpact.impact.validation import InputError


def typed_value(name: str, value):
    """``value`` as typed (a text stripped), or None when it is not given; ``InputError`` naming ``name`` for
    anything but a number or a text."""
    if value is None or (isinstance(value, str) and not value.strip()):
        return None
    if not isinstance(value, (str, int, float)) or isinstance(value, bool):
        raise InputError(f"{name} must be a number or a text; got {value!r}", name)
    return value.strip() if isinstance(value, str) else value


def read_request(request, names, flags=()) -> dict:
    """The inputs of ``request`` given (module docstring): ``names`` allowed, ``flags`` among them true or false
    (false: not given)."""
    if not isinstance(request, dict):
        raise InputError("the request must be a JSON object of inputs", "request")
    inputs = {}
    for name, value in request.items():
        if name not in names:
            raise InputError(f"unknown input {name!r} (inputs: {', '.join(names)})", name)
        if name in flags:
            if not isinstance(value, bool):
                raise InputError(f"{name} must be true or false; got {value!r}", name)
            if value:
                inputs[name] = True
            continue
        value = typed_value(name, value)
        if value is not None:
            inputs[name] = value
    return inputs


__all__ = ["read_request", "typed_value"]
