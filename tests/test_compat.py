"""Every dolfinx/ufl/basix/petsc4py-version-specific call lives in ``fe_beam/fem/compat.py``
(issue 13): the names below differ between Debian's dolfinx 0.5.2 and PyPI's 0.10/0.11 (or are
internals that move between versions) and must not appear anywhere else in the repository's
Python code. A new one found in a version move belongs in this list and in compat."""

import re
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
COMPAT = ROOT / "fe_beam" / "fem" / "compat.py"

# (pattern, what replaces it)
VERSION_SPECIFIC = [
    (r"\bFiniteElement\b", "compat.element / compat.quadrature_element"),
    (r"\bVectorElement\b", "compat.vector_element"),
    (r"\bTensorElement\b", "a compat function"),
    (r"\bMixedElement\b", "compat.mixed_element"),
    (r"\bbasix\.ufl\b|\bufl_wrapper\b", "compat's element functions"),
    (r"(?<!compat\.)\bFunctionSpace\(", "compat.function_space"),
    (r"\bVectorFunctionSpace\b", "compat.function_space(mesh, compat.vector_element(...))"),
    (r"(?<!compat\.)\bfunctionspace\(", "compat.function_space"),
    (r"\.vector\b", "compat.vector_of(function)"),
    (r"\bpetsc_vec\b", "compat.vector_of(function)"),
    (r"\bgmshio\b|\bdolfinx\.io\.gmsh\b|from dolfinx\.io import gmsh", "compat.gmsh_model_to_mesh"),
    (r"\bBoundingBoxTree\b|\bbb_tree\b|\bcompute_collisions", "compat.bounding_box_tree"),
    (r"(?<!compat\.)\bcreate_vector\(", "compat.create_vector(form)"),
    (r"(?<!compat\.)\bcreate_matrix\(", "compat.create_matrix(form)"),
    (r"\bfem\.petsc\b|\bfem_petsc\b", "compat's assembly wrappers"),
    (r"(?<!compat\.)(?<!fem\.)\bassemble_matrix\(|(?<!compat\.)\bapply_lifting\(",
     "compat's wrappers"),
    (r"(?<!compat\.)\bset_bc\(|(?<!compat\.)\bassemble_vector\(.*\bPETSc\b", "compat's wrappers"),
    (r"\bDirichletBCMetaClass\b|\bFormMetaClass\b", "compat.DirichletBC"),
    (r"\bdolfinx\.cpp\b|\bperm_vtk\b|\bentities_to_geometry\b", "a compat function"),
    (r"\bgeometry\.dofmap\b|\bdofmap\.list\b", "compat.geometry_cell_nodes / compat.cell_dofs"),
    (r"\bufl_element\(\)|\bufl_coordinate_element\b", "compat.element_degree / geometry_degree"),
    (r"\binterpolation_points\b", "compat.interpolation_expression"),
    (r"\bfem\.Expression\(", "compat.expression / compat.interpolation_expression"),
    (r"(?<!compat\.)\bcreate_mesh\(", "compat.create_interval_from_vertices"),
    (r"\batan_2\b|\bufl\.atan2\b", "compat.atan2"),
    (r"\bpushErrorHandler\(", "compat.push_quiet_petsc_error_handler"),
    (r"\bgmsh\.initialize\(", "compat.gmsh_initialize"),
]


def python_files():
    for folder in ("fe_beam", "tests", "benchmarks", "demos", "postprocessing"):
        for path in sorted((ROOT / folder).rglob("*.py")):
            if path != COMPAT and path != Path(__file__).resolve():
                yield path


def code_lines(path: Path):
    """(line number, code without its comment) of every line of ``path``."""
    for number, line in enumerate(path.read_text().splitlines(), start=1):
        yield number, line.split("#", 1)[0]


@pytest.mark.parametrize("pattern, instead", VERSION_SPECIFIC, ids=lambda v: str(v)[:40])
def test_version_specific_names_only_in_compat(pattern, instead):
    regex = re.compile(pattern)
    found = [f"{path.relative_to(ROOT)}:{number}: {code.strip()}"
             for path in python_files() for number, code in code_lines(path)
             if regex.search(code)]
    assert not found, f"use {instead} (fe_beam/fem/compat.py) instead of:\n" + "\n".join(found)


def test_the_grep_sees_the_package_and_would_catch_a_use():
    """The file walk covers the package and the tests, and each pattern matches the call it
    names: a pattern with a typo would pass on any code."""
    files = {p.relative_to(ROOT).as_posix() for p in python_files()}
    assert {"fe_beam/fem/rod.py", "fe_beam/solvers/solid.py", "tests/test_beam.py"} <= files
    samples = [
        'ufl.FiniteElement("Lagrange", cell, 1)', "ufl.VectorElement('P', c, 2)",
        "ufl.TensorElement('P', c, 1)", "ufl.MixedElement([a, b])", "basix.ufl.element('P')",
        "fem.FunctionSpace(msh, e)", "fem.VectorFunctionSpace(msh, ('P', 1))",
        "fem.functionspace(msh, e)", "x = u.vector", "u.x.petsc_vec",
        "from dolfinx.io import gmshio",
        "geometry.bb_tree(msh, 3)", "fem.petsc.create_vector(L)", "fem.petsc.create_matrix(a)",
        "import dolfinx.fem.petsc as fem_petsc", "assemble_matrix(a, bcs, diagonal=1.0)",
        "set_bc(b, bcs)", "fem.DirichletBCMetaClass", "from dolfinx.cpp.io import perm_vtk",
        "msh.geometry.dofmap", "V.ufl_element().degree()", "V.element.interpolation_points",
        "fem.Expression(e, X)", "mesh.create_mesh(comm, c, x, d)", "ufl.atan_2(y, x)",
        "PETSc.Sys.pushErrorHandler('ignore')", "gmsh.initialize()",
    ]
    for pattern, _ in VERSION_SPECIFIC:
        assert any(re.search(pattern, sample) for sample in samples), pattern
    allowed = ["compat.function_space(msh, e)", "compat.vector_of(u)", "compat.create_vector(L)",
               "compat.assemble_matrix(a, bcs=bcs, diagonal=0.0)", "compat.vector_element(m)"]
    for sample in allowed:
        assert not any(re.search(p, sample) for p, _ in VERSION_SPECIFIC), sample


def test_compat_module_provides_what_the_list_points_to():
    """Every compat function named as the replacement exists (on the running stack)."""
    from fe_beam.fem import compat

    names = set(re.findall(r"compat\.(\w+)", " ".join(i for _, i in VERSION_SPECIFIC)))
    missing = [name for name in sorted(names) if not hasattr(compat, name)]
    assert not missing, missing
