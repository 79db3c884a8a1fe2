"""Where the package finds the DBC and the parameter table.

Run from the repository's source tree (tools/mdtool/src, as
tools/can/mc_can.py and the tests do), the package reads the repository's
own files, tools/can/motordrive.dbc and tools/config/params_meta.json: the
firmware generator reads the same DBC, so there is one copy. Installed
(pip install ./tools/mdtool), the package carries copies of both made at
install time (tools/mdtool/CMakeLists.txt installs them into
mdtool/can/data/); `ctest -R can.mdtool_data` checks they equal the
repository's files. MDTOOL_DBC / MDTOOL_PARAMS_META override both.
"""
import os

HERE = os.path.dirname(os.path.abspath(__file__))
_REPO = os.path.normpath(os.path.join(HERE, "..", "..", "..", "..", ".."))
_DATA = os.path.join(HERE, "data")


def _find(env, repo_rel, name):
    if os.environ.get(env):
        return os.environ[env]
    repo = os.path.join(_REPO, repo_rel)
    if os.path.isfile(repo) and os.path.isfile(os.path.join(_REPO, "tools", "mdtool", "pyproject.toml")):
        return repo
    return os.path.join(_DATA, name)


def dbc_path():
    """The DBC: the repository's tools/can/motordrive.dbc, else the installed copy."""
    return _find("MDTOOL_DBC", os.path.join("tools", "can", "motordrive.dbc"), "motordrive.dbc")


def params_meta_path():
    """params_meta.json: the repository's tools/config/, else the installed copy."""
    return _find("MDTOOL_PARAMS_META", os.path.join("tools", "config", "params_meta.json"),
                 "params_meta.json")


def repo_root():
    """The repository when running from its source tree, else None."""
    return _REPO if os.path.isfile(os.path.join(_REPO, "tools", "mdtool", "pyproject.toml")) else None
