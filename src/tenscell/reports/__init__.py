"""Reports: Markdown rendered only from result fields, one module per kind of result.

Nothing here computes physics; every number printed comes from a result object
that the run produced from its own inputs.
"""
