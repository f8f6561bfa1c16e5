"""tsim.backend.runtime gives Taichi's AST transformer a lighter source position (file, line,
function and the source line, without Taichi's caret drawing): a kernel's compile error still says
where it is."""

import inspect

import pytest
import taichi as ti

from tsim.backend import runtime


def test_a_kernels_compile_error_names_its_file_line_function_and_source():
    runtime.init()

    @ti.kernel
    def broken() -> ti.i32:
        return no_such_name_in_this_kernel + 1  # noqa: F821 - the error

    line = inspect.getsourcelines(broken.__wrapped__ if hasattr(broken, "__wrapped__") else broken)[1]
    with pytest.raises(Exception) as err:
        broken()
    msg = str(err.value)
    assert f'File "{__file__}", line {line + 2}, in broken:' in msg, msg
    assert "return no_such_name_in_this_kernel + 1" in msg and "is not defined" in msg, msg


def test_the_lighter_position_is_the_one_taichi_uses():
    """Taichi 1.7 has the method the runtime replaces (a newer Taichi without it: this fails, and
    the replacement, which then does nothing, should be looked at again)."""
    from taichi.lang.ast.ast_transformer_utils import ASTTransformerContext

    assert ASTTransformerContext.get_pos_info is runtime._source_line_info
