import gc

gc.disable()        # `python -m linkbook`: the imports too run without the cyclic collector
from .cli import main  # noqa: E402  (main pauses it as well, for the `linkbook` script)

raise SystemExit(main())
