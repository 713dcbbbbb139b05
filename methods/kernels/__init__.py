"""Kernel templates: plain Python functions whose free names are bound in a generated module.

Each template module imports its free names from :mod:`gnibench.methods.kernels.free` only so that it is
valid, lintable Python; :func:`gnibench.suite.cell.codegen.template` copies the function sources into the cell's
generated module, where those names are the cell's own compiled functions and constants.
"""
