"""Package version and the core version recorded in every FMU.

``CORE_VERSION`` is the package version plus a digest of the core's Python sources. An FMU
records the core version it was built from and carries a private copy of the core named after
it (:mod:`altfusion.fmi.bundle`), whose ``bundle.json`` (:data:`BUNDLE`) states that version
and the modules copied; the runner's in-process core backend steps its own copy, so it refuses
FMUs built from another core.
"""

import hashlib
import json
from pathlib import Path

__version__ = "0.1.0"


def source_digest(package_dir: Path | None = None) -> str:
    """Short SHA-256 digest over the relative paths and contents of the package's .py files."""
    root = Path(package_dir or Path(__file__).parent)
    digest = hashlib.sha256()
    for path in sorted(root.rglob("*.py")):
        if "__pycache__" in path.parts:
            continue
        digest.update(path.relative_to(root).as_posix().encode())
        digest.update(path.read_bytes())
    return digest.hexdigest()[:12]


BUNDLE_MANIFEST = "bundle.json"
_MANIFEST_PATH = Path(__file__).with_name(BUNDLE_MANIFEST)
BUNDLE: dict | None = json.loads(_MANIFEST_PATH.read_text()) if _MANIFEST_PATH.exists() else None
"""A private copy's manifest: its ``core_version`` and ``modules``; None when installed."""

CORE_VERSION = BUNDLE["core_version"] if BUNDLE else f"{__version__}+{source_digest()}"
