"""Sweeps: many closed-loop runs (suites x controllers x K x latency modes x seeds),
executed on local processes or Ray, tabulated, plotted and reported as one HTML page.

``plan``: the settings and the list of runs; ``execute``: one run into its folder, and
the backends; ``ncap``: Euro NCAP's view of a threat run; ``tables``: results.csv and
the per-configuration summary; ``plots`` and ``report``: the PNGs and report.html;
``sweep``: the whole pipeline, as ``bittc sweep`` and ``bittc demo`` call it.
"""
