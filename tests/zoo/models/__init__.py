"""Zoo models, one module per system; each defines ``CASE``, a :class:`tests.zoo.case.ZooCase`."""
