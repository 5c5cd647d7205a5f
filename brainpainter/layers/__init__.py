"""Layer kinds and readers as plugins (entry-point groups ``brainpainter.layers`` and
``brainpainter.readers``): what a file is (:mod:`.readers`), the built-in readers
(:mod:`.builtin_readers`), what a layer kind is and the built-in kinds (:mod:`.kinds`)."""
