"""The plane of sigma and a second parameter by brute force (``impact-harness atlas``): the run and
its files (:mod:`.run`), the attractor classes and where each is stable (:mod:`.classes`), the chart's
continued edges checked against the pixels (:mod:`.curves`), atlas.nc (:mod:`.dataset`), atlas.png
(:mod:`.figure`) and report.md (:mod:`.report`)."""
