"""The reproduction report: each capability contributes a section (see :mod:`fsrlab.reports.paper`)."""
