"""Where every second of the default decompose() goes: ``python perf/profile.py --help``.

The profile itself is :mod:`profile_decompose` (this folder).  This file has
a second role: a script run from ``perf/`` puts this folder first on
``sys.path``, and ``cProfile`` (which Warp imports) imports the standard
library's ``profile`` module by that name, so when imported (not run) this
module loads the standard library's ``profile`` and takes its contents.
"""
import os
import sys
import sysconfig

if __name__ == "__main__":
    sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
    from profile_decompose import main

    main()
else:
    import importlib.util

    _spec = importlib.util.spec_from_file_location(
        __name__, os.path.join(sysconfig.get_paths()["stdlib"], "profile.py"))
    _std = importlib.util.module_from_spec(_spec)
    _spec.loader.exec_module(_std)
    globals().update({k: v for k, v in vars(_std).items() if not k.startswith("__")})
    __all__ = _std.__all__
