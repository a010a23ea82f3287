"""What an artifact was made from: fingerprints of the case content and of the input artifacts.

Every artifact carries a `Provenance` (`made_from` in JSON, a `meta_made_from` entry in .npz):
  case_fingerprint  sha256 of the parsed, validated case (geometry.params' dataclasses serialised
                    with sorted keys): comments, layout, number spelling (1 vs 1.0) and the file's
                    path do not count; any value that reaches a stage does;
  inputs            the fingerprints of the artifacts it was computed from (e.g. the mesh of the
                    stiffness);
  artifact          the artifact's schema id (a schema change makes every old file a stranger);
  fingerprint       sha256 of those three: what a later artifact lists among its own inputs.
A stage given an artifact whose case fingerprint is not its own case's refuses it (`check`): one
line naming both cases, both fingerprints and the command that rebuilds the artifact.
"""
from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass

from geometry.artifacts import InputError

FINGERPRINT_VERSION = 1   # bump when the canonical serialisation below changes
SHOWN_HEX = 12            # digits of a fingerprint quoted in messages


class FingerprintError(InputError):
    """An artifact made from another case (or another version of it), or with no fingerprint."""


def _sha256(data) -> str:
    blob = json.dumps(data, sort_keys=True, separators=(",", ":"), allow_nan=False)
    return hashlib.sha256(blob.encode()).hexdigest()


def case_fingerprint(case) -> str:
    """sha256 of the validated case content (ReducerCase.to_dict(): every section, name included,
    the source path excluded)."""
    return _sha256({"fingerprint_version": FINGERPRINT_VERSION, "case": case.to_dict()})


def file_fingerprint(path) -> str:
    """sha256 of a file's bytes: the fingerprint of an input that is not an artifact (a bench record)."""
    h = hashlib.sha256()
    with open(path, "rb") as fh:
        for block in iter(lambda: fh.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def short(fingerprint: str) -> str:
    return fingerprint[:SHOWN_HEX] + ("..." if len(fingerprint) > SHOWN_HEX else "")


@dataclass(frozen=True)
class Provenance:
    artifact: str                    # schema id of the artifact, e.g. "rv-stiffness/2"
    case_name: str
    case_fingerprint: str
    inputs: tuple = ()               # ((input name, its fingerprint), ...), sorted by name
    case_source: str = ""            # the case file it was read from (messages only, not hashed)

    @property
    def fingerprint(self) -> str:
        return _sha256({"fingerprint_version": FINGERPRINT_VERSION, "artifact": self.artifact,
                        "case": self.case_fingerprint, "inputs": dict(self.inputs)})

    def to_json(self) -> dict:
        return {"artifact": self.artifact, "case": self.case_name, "case_source": self.case_source,
                "case_fingerprint": self.case_fingerprint, "inputs": dict(self.inputs),
                "fingerprint": self.fingerprint}

    @classmethod
    def from_json(cls, data, where: str) -> "Provenance":
        """Read `made_from`; a missing entry or one whose fingerprint does not match its own
        content (hand-edited, truncated) is refused."""
        if not isinstance(data, dict):
            raise FingerprintError(f"{where}: no fingerprint (made_from = {data!r}); it predates "
                                   f"fingerprints or was not made by this pipeline: rebuild it")
        try:
            inputs = data["inputs"]
            prov = cls(str(data["artifact"]), str(data["case"]), str(data["case_fingerprint"]),
                       tuple(sorted((str(k), str(v)) for k, v in inputs.items())),
                       str(data.get("case_source", "")))
            stored = str(data["fingerprint"])
        except (KeyError, TypeError, AttributeError) as exc:
            raise FingerprintError(f"{where}: made_from is malformed (missing or bad entry {exc}); "
                                   f"rebuild it") from None
        if stored != prov.fingerprint:
            raise FingerprintError(f"{where}: made_from fingerprint {short(stored)} does not match its "
                                   f"own content ({short(prov.fingerprint)}): the file was edited; "
                                   f"rebuild it")
        return prov

    def check(self, case, where: str, rerun: str, artifact: str | None = None) -> None:
        """Refuse an artifact made from another case, another version of `case`, or another schema.
        `rerun` is the command that rebuilds it (quoted in the message)."""
        if artifact is not None and self.artifact != artifact:
            raise FingerprintError(f"{where} is a {self.artifact!r} artifact, this stage reads "
                                   f"{artifact!r}: rerun `{rerun}`")
        want = case_fingerprint(case)
        if self.case_fingerprint != want:
            made = ", ".join(filter(None, (self.case_source, f"fingerprint {short(self.case_fingerprint)}")))
            same = " with other content" if self.case_name == case.name else ""
            here = ", ".join(filter(None, (f"case {case.name!r}{same}", f"fingerprint {short(want)}")))
            raise FingerprintError(f"{where} was made from case {self.case_name!r} ({made}), not from "
                                   f"{case.source or 'this case'} ({here}): rerun `{rerun}`")


def made_from(case, artifact: str, **inputs) -> Provenance:
    """The provenance of an artifact of `case`; inputs: name -> Provenance or fingerprint string
    (None entries are left out: an optional input that was not given)."""
    items = tuple(sorted((k, v.fingerprint if isinstance(v, Provenance) else str(v))
                         for k, v in inputs.items() if v is not None))
    return Provenance(artifact, case.name, case_fingerprint(case), items, case.source)


__all__ = ["FINGERPRINT_VERSION", "FingerprintError", "Provenance", "case_fingerprint", "file_fingerprint",
           "made_from", "short"]
