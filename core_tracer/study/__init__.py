"""Design studies: the definition (``definition``), the parallel run (``run``, ``worker``) and the
contact sheet (``sheet``)."""
