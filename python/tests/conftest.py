"""The tests keep what they compute in the Rust tests' own cache folder beside the build
(`target/release/test-cache`), never in the user's: the package and the command line they
compare it with both read `XDG_CACHE_HOME`."""

import os
import pathlib

ROOT = pathlib.Path(__file__).resolve().parents[2]
os.environ["XDG_CACHE_HOME"] = str(ROOT / "target" / "release" / "test-cache")
