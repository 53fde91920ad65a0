"""What a local pool's worker process knows of its pool: the pool's stop event, set as the worker
starts (``local_pool._start_worker``) and polled by a task's stop flag (``cells.stop_flag``); None
in every other process."""

from __future__ import annotations

stop = None
