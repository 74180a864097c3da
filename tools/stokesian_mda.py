"""Open a stokesian H5MD trajectory with MDAnalysis (docs/output.md).

stokesian stores lengths in the reference radius a and times in mu a^3 / kT (docs/units.md) and
says so in H5MD `unit` attributes ("a", "mu a+3 kT-1", ...). MDAnalysis's H5MD reader knows only
physical units (Angstrom, nm, ps, ...) and refuses any other unit string, even with
convert_units=False. This module registers a reader that accepts the reduced units and never
converts them, and builds a Universe (MDAnalysis needs a topology: N atoms, one residue, radii
from the file):

    import sys; sys.path.insert(0, "tools")     # this folder
    from stokesian_mda import universe
    u = universe("out.h5")
    for ts in u.trajectory:
        ts.positions, ts.dimensions, ts.time     # in a and mu a^3/kT, box as [Lx Ly Lz alpha beta gamma]
"""
import h5py
import MDAnalysis as mda
from MDAnalysis.coordinates.H5MD import H5MDReader

# The unit strings stokesian writes (engine/core/frame.hpp, namespace units), per MDAnalysis kind.
REDUCED_UNITS = {
    "time": "mu a+3 kT-1",
    "length": "a",
    "velocity": "kT mu-1 a-2",
    "force": "kT a-1",
}


class StokesianH5MDReader(H5MDReader):
    """H5MD reader for stokesian trajectories: reduced units kept as they are."""

    format = "STOKESIAN_H5MD"
    _unit_translation = {kind: dict(table) for kind, table in H5MDReader._unit_translation.items()}
    for _kind, _unit in REDUCED_UNITS.items():
        # h5py returns H5MD's fixed-length string attributes as bytes: accept both spellings.
        _unit_translation[_kind][_unit] = _unit
        _unit_translation[_kind][_unit.encode()] = _unit

    def __init__(self, filename, **kwargs):
        kwargs["convert_units"] = False  # MDAnalysis has no conversion for a and mu a^3/kT
        super().__init__(filename, **kwargs)


def universe(path):
    """A Universe over the trajectory at `path` (one atom per particle, radii of the first frame)."""
    with h5py.File(path, "r") as f:
        n = f["particles/all/position/value"].shape[1]
        radius = f["particles/all/radius/value"][0]
    u = mda.Universe.empty(n, trajectory=False)
    u.load_new(path, format=StokesianH5MDReader)
    u.add_TopologyAttr("radii", radius)
    return u
