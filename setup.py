"""The package list of gnibench, derived: the repository root is the import package ``gnibench``
(``package_dir = {"gnibench": "."}``) and its sub-packages are the folders with an
``__init__.py`` under the top-level package folders, found by setuptools' own discovery
(:func:`setuptools.find_packages`). The metadata, dependencies and package data are in
pyproject.toml. tests/test_layout.py checks the list against the folders, and that a wheel holds
every package, its data, and not this file."""
from setuptools import find_packages, setup
from setuptools.command.build_py import build_py

#: the top-level folders that are sub-packages of gnibench (the layout: README, "Layout")
PACKAGE_FOLDERS = ("suite", "problems", "methods", "reports")


def packages(root: str = ".") -> list[str]:
    """``gnibench`` and every package under the package folders, as ``gnibench.<dotted path>``."""
    found = find_packages(root, include=[f"{name}{tail}" for name in PACKAGE_FOLDERS
                                         for tail in ("", ".*")])
    return ["gnibench", *(f"gnibench.{name}" for name in sorted(found))]


class BuildPy(build_py):
    """The modules of the package ``gnibench`` (the repository root) but this build script."""

    def find_package_modules(self, package, package_dir):
        return [m for m in super().find_package_modules(package, package_dir)
                if (m[0], m[1]) != ("gnibench", "setup")]


if __name__ == "__main__":
    setup(packages=packages(), package_dir={"gnibench": "."}, cmdclass={"build_py": BuildPy})
