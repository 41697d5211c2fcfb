"""Learning the fuzzy sets: the codec from genes to partitions (:mod:`flctool.sets.codec`)
and the measures that show a learned partition is still readable
(:mod:`flctool.sets.measures`)."""
