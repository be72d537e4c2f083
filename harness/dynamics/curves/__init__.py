"""Event curves in two parameters: flip, fold and Neimark-Sacker (:mod:`.event_curves`), grazes
(:mod:`.graze_curves`), the curve type (:mod:`.curve`) and the sigma coordinate they use (:mod:`.sigma_axis`)."""
