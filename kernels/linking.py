"""Machine code only where it runs: the inner kernels' code is optimised and emitted once, in
the kernel called from Python.

numba finalises each compiled function as a library: it links in the finished libraries of
the functions it calls, optimises the whole module and hands it to the JIT engine, which
emits machine code for all of it. A caller then links its callees' code and does the same
again. The pendulum's call tree is deep (entry point, block, a start, the steady state, the
transient, a section, a flight, a step), so its leaves were optimised and emitted once per
level above them, while only the entry point's own copy ever runs: an inner kernel
(``INNER_OPTIONS``) has no Python wrapper, and its callers call their own inlined or linked
copy, never the engine's.

Here a library compiled with neither a Python nor a C wrapper (nothing outside numba's
code can call it or take its address) is finalised lean: its code is kept as lowered, for
its callers to link, and the engine gets only its environment pointer, which numba sets
after every compile. Its callers optimise it with their own code, in one pass over the
whole tree instead of one per level. A kernel called from Python, or a ``cfunc``, is
finalised as before.

With a numba whose internals differ (the names patched below), nothing is changed: the
compile is slower, the results the same. tests/test_linking.py checks that the patch is
in place, that a kernel calling lean ones and a ``cfunc`` run, and
benchmarks/reference_atlases.py that the atlases are unchanged.
"""

import llvmlite.binding as ll
import llvmlite.ir as llvmir

#: the prefix of the global that holds a numba function's environment pointer
ENVIRONMENT_PREFIX = "_ZN08NumbaEnv"


def _defines(module, name: str) -> bool:
    try:
        return not module.get_function(name).is_declaration
    except NameError:
        return False


def _environment_module(library):
    """An LLVM module of the library's environment globals alone (what numba's set_env
    writes to after the compile)."""
    module = library._codegen._create_empty_module(library.name + ".environment")
    pointer = llvmir.IntType(8).as_pointer()
    for variable in library._final_module.global_variables:
        if variable.name.startswith(ENVIRONMENT_PREFIX) and not variable.is_declaration:
            kept = llvmir.GlobalVariable(module, pointer, name=variable.name)
            kept.linkage = "common"
            kept.initializer = llvmir.Constant(pointer, None)
    return ll.parse_assembly(str(module))


#: what is patched: numba's CPU context and JIT library (written against numba 0.68)
_NEEDED = {"CPUContext": ("get_executable",),
           "JITCodeLibrary": ("_optimize_final_module", "_finalize_final_module",
                              "_finalize_dynamic_globals", "_verify_declare_only_symbols"),
           "JITCPUCodegen": ("_create_empty_module", "_add_module")}


def install() -> bool:
    """Finalise the libraries of inner kernels lean (see the module); False where this
    numba lacks what is patched."""
    try:
        from numba.core import codegen, cpu
    except ImportError:
        return False
    classes = {"CPUContext": cpu.CPUContext, "JITCodeLibrary": codegen.JITCodeLibrary,
               "JITCPUCodegen": codegen.JITCPUCodegen}
    if not all(hasattr(classes[c], name) for c, names in _NEEDED.items() for name in names):
        return False
    context, library_class = cpu.CPUContext, codegen.JITCodeLibrary
    if getattr(context.get_executable, "lean", False):
        return True
    get_executable = context.get_executable
    optimize_final_module = library_class._optimize_final_module
    finalize_final_module = library_class._finalize_final_module

    def marking_get_executable(self, library, fndesc, env):
        if isinstance(library, library_class) and not library._finalized and not any(
                _defines(library._final_module, name) for name in
                (fndesc.llvm_cpython_wrapper_name, fndesc.llvm_cfunc_wrapper_name)):
            library.lean = True
        return get_executable(self, library, fndesc, env)
    marking_get_executable.lean = True

    def lean_optimize_final_module(self):
        if not getattr(self, "lean", False):
            optimize_final_module(self)

    def lean_finalize_final_module(self):
        if not getattr(self, "lean", False):
            return finalize_final_module(self)
        self._finalize_dynamic_globals()
        self._verify_declare_only_symbols()
        self._codegen._add_module(_environment_module(self))
        self._codegen._engine.finalize_object()
        self._finalized = True

    context.get_executable = marking_get_executable
    library_class._optimize_final_module = lean_optimize_final_module
    library_class._finalize_final_module = lean_finalize_final_module
    return True
