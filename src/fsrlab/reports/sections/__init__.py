"""Report section builders, one per capability; each exposes ``build(outdir) -> Section``.

Modules whose name starts with an underscore are helpers of a builder (e.g. its errata wording).
"""
