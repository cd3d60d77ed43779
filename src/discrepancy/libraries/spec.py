"""Libraries from short text specs such as ``"poly(3)+fourier(1)"`` (for the CLI).

Grammar (parsed, never evaluated)::

    spec   := product ("+" product)*
    product:= factor ("*" factor)*
    factor := NAME "(" INT ("," VARIABLE)* ")"

``NAME`` is ``poly`` (degree) or ``fourier`` (number of frequencies); the optional
variables restrict the factor, e.g. ``fourier(1, phi1) * poly(1, u)``.
"""
from __future__ import annotations

import re

from ..errors import ParameterError, short_repr
from .base import FeatureLibrary
from .fourier import FourierLibrary
from .polynomial import PolynomialLibrary

TOKEN = re.compile(r"\s*(?:(?P<int>\d+)|(?P<name>[A-Za-z_][A-Za-z0-9_]*)|(?P<op>[()+*,]))")
MAX_DIGITS = 100
FACTORIES = {
    "poly": lambda k, v: PolynomialLibrary(degree=k, variables=v),
    "fourier": lambda k, v: FourierLibrary(n_frequencies=k, variables=v),
}


def _tokens(spec: str) -> list[str]:
    out, pos = [], 0
    spec = spec.strip()
    label = f"library spec {short_repr(spec)}"
    while pos < len(spec):
        m = TOKEN.match(spec, pos)
        if not m or m.end() == pos:
            raise ParameterError(f"{label}: unexpected character at position {pos}: "
                                 f"{spec[pos]!r}")
        out.append(m.group(m.lastgroup))
        pos = m.end()
    return out


def parse_library(spec: str) -> FeatureLibrary:
    """A library from a spec like ``"poly(3)+fourier(1)"`` or ``"poly(2)*poly(1, u)"``."""
    if not isinstance(spec, str):
        raise ParameterError(f"library spec must be text such as 'poly(3)+fourier(1)'; got "
                             f"{type(spec).__name__}")
    tokens = _tokens(spec)
    label = f"library spec {short_repr(spec)}"
    pos = 0

    def expect(what):
        nonlocal pos
        if pos >= len(tokens):
            raise ParameterError(f"{label}: expected {what} at the end")
        tok = tokens[pos]
        pos += 1
        return tok

    def factor():
        name = expect("a library name")
        if name not in FACTORIES:
            raise ParameterError(f"{label}: unknown library {name!r}; valid: "
                                 f"{', '.join(FACTORIES)}")
        if expect("'('") != "(":
            raise ParameterError(f"{label}: expected '(' after {name}")
        k = expect("an integer")
        if not k.isdigit() or len(k) > MAX_DIGITS:
            raise ParameterError(f"{label}: {name} needs an integer of at "
                                 f"most {MAX_DIGITS} digits, got {short_repr(k)}")
        variables = []
        while (tok := expect("')'")) == ",":
            variables.append(expect("a variable name"))
        if tok != ")":
            raise ParameterError(f"{label}: expected ')' or ',' after {name}")
        return FACTORIES[name](int(k), variables or None)

    def product():
        nonlocal pos
        lib = factor()
        while pos < len(tokens) and tokens[pos] == "*":
            pos += 1
            lib = lib * factor()
        return lib

    lib = product()
    while pos < len(tokens) and tokens[pos] == "+":
        pos += 1
        lib = lib + product()
    if pos != len(tokens):
        raise ParameterError(f"{label}: unexpected {tokens[pos]!r}")
    return lib
