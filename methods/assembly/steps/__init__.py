"""The step writers, one module per family: the text of ``make_ws`` and ``step(y, h, par, ws)``
(and ``step_sum`` under ``sum=compensated``; the attempt and controller of an adaptive family)
for one cell, unrolled over its state where that is faster (the bindings of each family:
:mod:`gnibench.methods.assembly.bindings`)."""
