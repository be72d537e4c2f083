"""The quantifiers of a basin scan: fractions, entropies and the uncertainty exponent
(:mod:`.measures`), from random pairs of starts (:mod:`.uncertainty`), the agreement of the batch
kernel with the FMU (:mod:`.agreement`), and their lines in a scan's Dataset and report (:mod:`.summary`)."""
