"""No import cycles among the modules of ``rnsca`` and ``service``, module by module.

The layer rules are import-linter contracts in pyproject.toml (``lint-imports``, run by
``make lint``). Their cycle contract (``acyclic_siblings``) compares the children of each
package, so it misses a cycle through a package's own ``__init__`` (``rnsca`` importing
``rnsca.clip``, which imports ``rnsca``): this test looks at every module.
"""

import grimp
import pytest


@pytest.fixture(scope="module")
def graph():
    return grimp.build_graph("rnsca", "service", cache_dir=None)


def import_cycles(graph):
    """Strongly connected components of more than one module (Tarjan, iteratively)."""
    index, low, on_stack, stack, cycles = {}, {}, set(), [], []
    for root in sorted(graph.modules):
        if root in index:
            continue
        work = [(root, iter(sorted(graph.find_modules_directly_imported_by(root))))]
        index[root] = low[root] = len(index)
        stack.append(root)
        on_stack.add(root)
        while work:
            module, imported = work[-1]
            for other in imported:
                if other not in index:
                    index[other] = low[other] = len(index)
                    stack.append(other)
                    on_stack.add(other)
                    work.append(
                        (other, iter(sorted(graph.find_modules_directly_imported_by(other))))
                    )
                    break
                if other in on_stack:
                    low[module] = min(low[module], index[other])
            else:
                work.pop()
                if work:
                    parent = work[-1][0]
                    low[parent] = min(low[parent], low[module])
                if low[module] == index[module]:
                    component = []
                    while True:
                        member = stack.pop()
                        on_stack.discard(member)
                        component.append(member)
                        if member == module:
                            break
                    if len(component) > 1:
                        cycles.append(sorted(component))
    return cycles


def test_finds_a_cycle_through_a_package_init():
    graph = grimp.ImportGraph()
    for module in ("pkg", "pkg.a", "pkg.b"):
        graph.add_module(module)
    graph.add_import(importer="pkg", imported="pkg.a")
    graph.add_import(importer="pkg.a", imported="pkg")
    graph.add_import(importer="pkg.b", imported="pkg.a")
    assert import_cycles(graph) == [["pkg", "pkg.a"]]


def test_no_import_cycles(graph):
    cycles = import_cycles(graph)
    assert cycles == [], f"modules that import each other, directly or not: {cycles}"
