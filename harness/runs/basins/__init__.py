"""Basin scans over a grid of starts: through the FMU (:mod:`.scan`), on the batch kernel
(:mod:`.kernel_scan`) in tiles (:mod:`.tiles`) with the attractors found so far and the checkpoint
(:mod:`.registry`), and the tolerance balls that let one period label a start (:mod:`.ball`)."""
