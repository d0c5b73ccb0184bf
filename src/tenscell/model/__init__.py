"""What a structure is and where it rests: members, coordinates, equilibrium, reference shapes.

The public names of ``model/``'s modules (:mod:`~tenscell.model.structure`,
:mod:`~tenscell.model.equilibrium`, :mod:`~tenscell.model.formfinding`,
:mod:`~tenscell.model.shapes`, :mod:`~tenscell.model.lattices`, :mod:`~tenscell.model.prestress`), importable
from here.
"""
from .equilibrium import Cell, NotPrestressableError, equilibrate
from .formfinding import FormFindingError, FormFindingResult, find_form, pin_jointed, rigid_body_modes
from .prestress import VirialPrestress, virial_prestress
from .lattices import expanded_octahedron, lattice_cell, lattice_structure, sphere_cell, sphere_structure
from .shapes import (DEFAULT_DELTA, REGULAR_DELTA, cylindrical_cell, if_free_delta, nucleated_cell, nucleated_structure,
                     paper_cell, paper_structure, regular_cell, semiflexible_paper_cell)
from .structure import (ACTIN, INTERMEDIATE_FILAMENT, NUCLEUS, STRUT, Point, Structure, StructureError, cable_mask,
                        member_values)

__all__ = [
    # structures
    "Point", "Structure", "StructureError", "member_values", "ACTIN", "INTERMEDIATE_FILAMENT", "STRUT", "NUCLEUS",
    "cable_mask",
    # equilibrium and form-finding
    "Cell", "NotPrestressableError", "equilibrate", "FormFindingError", "FormFindingResult", "find_form",
    "pin_jointed", "rigid_body_modes",
    # the physical prestress (the tendons' virial stress)
    "VirialPrestress", "virial_prestress",
    # the paper's cell and its references
    "paper_cell", "paper_structure", "regular_cell", "cylindrical_cell", "semiflexible_paper_cell", "if_free_delta",
    "DEFAULT_DELTA", "REGULAR_DELTA", "nucleated_cell", "nucleated_structure",
    # spheres and lattices
    "sphere_cell", "sphere_structure", "lattice_cell", "lattice_structure", "expanded_octahedron",
]
