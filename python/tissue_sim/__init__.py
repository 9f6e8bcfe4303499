"""tissue-sim from Python: an anisotropic soft-tissue cube to press, drag and read.

    import tissue_sim as ts
    sim = ts.Simulation(ts.Material.object("A"))
    sim.press(ts.Press.normal((0.05, 0.05, 0.10), radius=0.015, depth=0.004))
    sim.run_for(1.0)
    r = sim.probe()      # r.force, r.force_n, r.depth_m, r.contact
    x = sim.positions()  # numpy array, shape (nodes, 3)

Units are SI (metres, newtons, seconds). The probe's force is the material's own (its surface
compliance, computed the first time for a material, about a minute, and kept in the cache folder).
"""

import json

import numpy as np

from . import _native
from ._native import Material, Press, ProbeReading

__all__ = ["Material", "Press", "ProbeReading", "Simulation", "calibrate", "palpate"]


class Simulation:
    """The running tissue, built with the viewer's defaults unless a keyword says otherwise:
    model ("hex", "shear", "axis", "fem-linear", "fem-corotational"), nodes (per edge, 8),
    integrator ("symplectic", "implicit", "prefactored", "newmark"; automatic by default),
    dt (1e-4 s), damping_ratio (0.2), contact ("surface" or "nodes")."""

    def __init__(self, material, **choices):
        self._sim = _native.Simulation(material, **choices)

    def press(self, press):
        """Puts the probe where the press says from the next step."""
        self._sim.press(press)

    def drag(self, node, target):
        """Pulls a node towards a point (metres) by the mouse's spring."""
        self._sim.drag(node, tuple(target))

    def release(self):
        """Lets go of the probe or the drag."""
        self._sim.release()

    def step(self):
        """One step (raises RuntimeError where the guard gave up on a blow-up, ValueError on a bad press)."""
        self._sim.step()

    def run_for(self, seconds):
        """Steps for that many simulated seconds."""
        self._sim.run_for(seconds)

    def probe(self):
        """The probe's reading of the last step while pressed, else None."""
        return self._sim.probe()

    def tool_force(self):
        """The tissue's force on the tool (probe or drag), N."""
        return np.array(self._sim.tool_force())

    def positions(self):
        """Node positions now, metres, shape (nodes, 3)."""
        return np.array(self._sim.positions_flat()).reshape(-1, 3)

    @property
    def time_s(self):
        """Simulated time, s."""
        return self._sim.time_s

    @property
    def dt(self):
        """The step the policy runs, s."""
        return self._sim.dt


def calibrate(material, **settings):
    """The paper's calibration as `tissue-sim calibrate` runs it (model, method, seed, population,
    generations, cases, nodes); its result as a dict (the command's JSON)."""
    return json.loads(_native.calibrate(material, **settings))


def palpate(material, **settings):
    """A palpation map of a face as `tissue-sim palpate` makes it (face, radius, depth, grid); as a
    dict (its map.json)."""
    return json.loads(_native.palpate(material, **settings))
