"""The problem registry: one line per problem. A new problem is one file plus one line here."""
from problems import double_oscillator, harmonic_oscillator, kepler_2d, lotka_volterra, pendulum

REGISTRY = {m.PROBLEM.id: m.PROBLEM for m in (
    harmonic_oscillator,
    double_oscillator,
    pendulum,
    kepler_2d,
    lotka_volterra,
)}
