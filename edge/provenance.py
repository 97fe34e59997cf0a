"""Kept for ``edge.infer.bundle``, which re-exports ``sha256_file`` from here: the helpers live in
:mod:`cavatar_common.provenance` (shared by edge, sim and export). New code imports that."""

from cavatar_common.provenance import git_revision, sha256_file

__all__ = ["git_revision", "sha256_file"]
