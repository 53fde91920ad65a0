"""Designs that search for themselves: an optimisation (``spec``) varies study parameters within
ranges, renders each trial on the Dask cluster (``trials``), scores it with measures (``measures``,
``ssim``) and lets Optuna choose the next (``search``); the results are presets, a contact sheet of
the best trials and the history plot (``results``)."""
