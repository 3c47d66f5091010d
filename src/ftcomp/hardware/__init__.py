"""The hardware seam: protocols a robot and a sensor implement (:mod:`.protocols`), backends by
URI (:mod:`.registry`) and fault injection (:mod:`.faults`)."""
