"""STEP/STL export of CadQuery solids: checked valid first, written atomically.

A solid that OpenCascade does not call valid (self-intersecting outline, failed boolean) is never
written: `InvalidSolidError` (an InputError: the case asked for an impossible part) names it.
STL tolerances are chordal/angular deflections of the tessellation, in mm and rad.
Same solid, same bytes: the STEP header's FILE_NAME (name, time stamp, author, organisation) is
written from fixed values instead of the clock, so a rerun reproduces every file exactly.
"""
from __future__ import annotations

import errno
from pathlib import Path

import cadquery as cq

from geometry.artifacts import InputError, atomic_path

STL_TOLERANCE_MM = 0.01        # chordal deflection [mm] (0.005 takes 40 s on a disc)
STL_ANGULAR_TOLERANCE_RAD = 0.1
STEP_TIME_STAMP = "1970-01-01T00:00:00"   # fixed: the clock would make every rerun differ
STEP_AUTHOR = "rvte"


class InvalidSolidError(InputError):
    """A solid that fails OpenCascade's validity check; nothing was written."""


def as_shape(obj: cq.Workplane | cq.Shape) -> cq.Shape:
    if isinstance(obj, cq.Workplane):
        vals = [v for v in obj.vals() if isinstance(v, cq.Shape)]
        if not vals:
            raise InvalidSolidError("the workplane holds no shape")
        return vals[0] if len(vals) == 1 else cq.Compound.makeCompound(vals)
    return obj


def check_valid(obj: cq.Workplane | cq.Shape, name: str) -> cq.Shape:
    """The shape, if valid and non-empty; else InvalidSolidError naming the part."""
    shape = as_shape(obj)
    if not shape.isValid():
        raise InvalidSolidError(f"{name}: the CAD solid is not valid (OpenCascade check failed); "
                                f"check the case's sizes for overlapping or degenerate features")
    if not shape.Solids():
        raise InvalidSolidError(f"{name}: the CAD result holds no solid")
    return shape


def export_step(obj: cq.Workplane | cq.Shape, path: str | Path, name: str | None = None) -> Path:
    path = Path(path)
    shape = check_valid(obj, name or path.stem)
    with atomic_path(path) as tmp:
        _write_step(shape, tmp, path.stem)
    return path


def _write_step(shape: cq.Shape, path: Path, name: str) -> None:
    """cadquery's Shape.exportStep (AP214, mm, pcurves) with a reproducible FILE_NAME header."""
    from OCP.APIHeaderSection import APIHeaderSection_MakeHeader
    from OCP.IFSelect import IFSelect_ReturnStatus
    from OCP.Interface import Interface_Static
    from OCP.STEPControl import STEPControl_AsIs, STEPControl_Writer
    from OCP.TCollection import TCollection_HAsciiString
    writer = STEPControl_Writer()
    Interface_Static.SetIVal_s("write.surfacecurve.mode", 1)
    Interface_Static.SetIVal_s("write.precision.mode", 0)
    Interface_Static.SetCVal_s("xstep.cascade.unit", "MM")
    Interface_Static.SetCVal_s("write.step.unit", "MM")
    writer.Transfer(shape.wrapped, STEPControl_AsIs)
    header = APIHeaderSection_MakeHeader(writer.Model())
    header.SetName(TCollection_HAsciiString(name))
    header.SetTimeStamp(TCollection_HAsciiString(STEP_TIME_STAMP))
    header.SetAuthorValue(1, TCollection_HAsciiString(STEP_AUTHOR))
    header.SetOrganizationValue(1, TCollection_HAsciiString(STEP_AUTHOR))
    if writer.Write(str(path)) != IFSelect_ReturnStatus.IFSelect_RetDone:
        raise OSError(errno.EIO, "OpenCascade could not write the STEP file", str(path))


def export_stl(obj: cq.Workplane | cq.Shape, path: str | Path, name: str | None = None, *,
               tolerance_mm: float = STL_TOLERANCE_MM,
               angular_tolerance_rad: float = STL_ANGULAR_TOLERANCE_RAD) -> Path:
    path = Path(path)
    shape = check_valid(obj, name or path.stem)
    with atomic_path(path) as tmp:
        cq.exporters.export(shape, str(tmp), exportType="STL", tolerance=tolerance_mm,
                            angularTolerance=angular_tolerance_rad)
    return path


def export_solid(obj: cq.Workplane | cq.Shape, out_dir: str | Path, name: str) -> list[Path]:
    """`name`.step and `name`.stl in out_dir (validity checked once, before either is written)."""
    out_dir = Path(out_dir)
    shape = check_valid(obj, name)
    return [export_step(shape, out_dir / f"{name}.step", name),
            export_stl(shape, out_dir / f"{name}.stl", name)]
