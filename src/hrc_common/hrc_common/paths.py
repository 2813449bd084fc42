"""Where the parameter files are: the one lookup of the ``params/`` directory (pure).

Every ``params/*.yaml`` (the nodes' parameter files, ``cases.yaml``, ``task_tree.yaml``,
``sim_human.yaml``) is installed to ``share/hrc_common/params/``. A source checkout uses its
own ``params/`` (``colcon build --symlink-install`` keeps the modules' real paths in ``src/``),
so an edited file takes effect without a rebuild.
"""

import pathlib

try:  # optional: a bare source tree without ROS has no ament index (only the checkout's files)
    from ament_index_python.packages import get_package_share_directory, PackageNotFoundError
except ImportError:
    get_package_share_directory = None

# <repository>/src/hrc_common/hrc_common/paths.py -> <repository>
_CHECKOUT = pathlib.Path(__file__).resolve().parents[3]


def params_dir() -> pathlib.Path:
    """Return the parameter files' directory.

    The checkout's ``params/`` when this code runs from a source tree, else the installed
    ``share/hrc_common/params/``.
    """
    local = _CHECKOUT / 'params'
    if (_CHECKOUT / 'src' / 'hrc_common').is_dir() and (local / 'cases.yaml').is_file():
        return local
    if get_package_share_directory is not None:
        try:
            return pathlib.Path(get_package_share_directory('hrc_common')) / 'params'
        except PackageNotFoundError:
            pass
    return local


def params_file(name: str) -> pathlib.Path:
    """Return ``params_dir() / name`` (e.g. ``params_file('task_tree.yaml')``)."""
    return params_dir() / name
