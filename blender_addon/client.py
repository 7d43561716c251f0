"""Where the `tessd` Python client comes from.

The installable zip carries a copy of python/tessd as `vendor/tessd` (made by build.py; the
add-on folder in git holds no copy). Running straight from the source tree, the client is
imported from wherever `tessd` is importable (e.g. python/ on sys.path).
"""

try:
    from .vendor import tessd
except ImportError:  # pragma: no cover - development from the source tree
    import tessd  # noqa: F401

__all__ = ["tessd"]
