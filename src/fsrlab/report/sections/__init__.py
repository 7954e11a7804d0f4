"""Report section builders, one per capability; each exposes ``build(outdir) -> Section``."""
