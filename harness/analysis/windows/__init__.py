"""The windows of one oscillator over sigma: the ODE's windows found by scans and shooting
(:mod:`.ode_windows`), their edges located by continuation (:mod:`.located_edges`) and reconciled
where theory says they coincide (:mod:`.edge_coincidence`), the parameter set (:mod:`.problem`), the
comparison with the maps' windows (:mod:`.compare_windows`, ``impact-harness windows``), its
summary (:mod:`.summary`), report (:mod:`.report`) and figures (:mod:`.plots`)."""
