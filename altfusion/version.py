"""Package version and the core version recorded in every FMU.

``CORE_VERSION`` is the package version plus a digest of the core's Python sources. An FMU
records the core version it was built from; since pythonfmu imports only the first bundled copy
of ``altfusion`` in a process, the runner refuses to mix FMUs built from different cores.
"""

import hashlib
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


CORE_VERSION = f"{__version__}+{source_digest()}"
