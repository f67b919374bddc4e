"""Parse one source line with Lark into the nodes of armctl/script/nodes.py.

Strategy: one LALR parser with the contextual lexer, built once on first use (module-level
cache, its tables kept across runs in the user's cache folder: ``cache_path``) from ``grammars/armctl.lark`` via ``Lark.open_from_package("armctl.grammars", …)`` —
the way it is found inside a wheel and in an editable install.  In a bare source checkout that
was never installed (``armctl.grammars`` is only a name given by pyproject.toml's package-dir)
the ``grammars/`` folder next to ``armctl/`` is registered under that name first.

``transformer=`` builds the nodes while the parser reduces, so no parse tree exists.  Value
rules return a transient ``_Spanned`` (node plus columns) so that each word knows where its
value ends; the outermost rules unwrap it.  A line that does not parse raises
``LineSyntaxError`` with a plain sentence (armctl/script/syntax_errors.py), never a token dump.
"""

from __future__ import annotations

import functools
import importlib
import importlib.util
import sys
from pathlib import Path
from typing import NamedTuple

from typing import TYPE_CHECKING

from .expressions import Binary, Negate, Parameter
from .nodes import EMPTY, Assignment, BlockLine, CodeLine, KeywordLine, Node, code_number
from .syntax_errors import LineSyntaxError, explain

if TYPE_CHECKING:  # Lark is imported on first use: most scripts never need it (fastpath.py)
    from lark import Lark

GRAMMAR_PACKAGE = "armctl.grammars"
GRAMMAR_FILE = "armctl.lark"

# Every way a word's letter can be written → its canonical name ('x' → 'X', 'j1=' → 'J1').
LETTERS: dict[str, str] = {}
for _code in range(ord("A"), ord("Z") + 1):
    LETTERS[chr(_code)] = LETTERS[chr(_code).lower()] = chr(_code)
for _joint in "123456":
    LETTERS[f"J{_joint}="] = LETTERS[f"j{_joint}="] = f"J{_joint}"


# Evaluation and printing of expressions recurse, so their depth is bounded (far beyond any
# real expression, far below Python's recursion limit).
MAX_EXPRESSION_DEPTH = 100


class _Spanned(NamedTuple):
    """A value node (float or expression) with the columns of its source text and its depth."""

    node: object
    column: int
    end_column: int
    depth: int = 0


def _deeper(node, column: int, end_column: int, depth: int) -> _Spanned:
    if depth > MAX_EXPRESSION_DEPTH:
        raise LineSyntaxError(
            f"expression nested more than {MAX_EXPRESSION_DEPTH} operations deep", column, end_column,
            "split it over several #<name> = … lines",
        )
    return _Spanned(node, column, end_column, depth)


def _split_word(text: str) -> tuple[str, str]:
    """'X-1.5' → ('X', '-1.5'); 'j2=30' → ('J2', '30'); 'X' → ('X', '')."""
    if len(text) >= 3 and text[2] == "=" and text[0] in "Jj":
        return LETTERS[text[:3]], text[3:]
    return LETTERS[text[0]], text[1:]


class _NodeBuilder:
    """Callbacks the LALR parser calls on each reduction (``transformer=``: Lark looks them up
    by rule name; no ``lark.Transformer`` base, so this module imports Lark only when a line
    needs it).  A ``LineSyntaxError`` raised here reaches ``parse_line``'s caller as it is."""

    # --- lines ------------------------------------------------------------------------------

    def start(self, children):
        for child in children:
            if not isinstance(child, str):  # skip a lone LINE_NUMBER (a lark.Token is a str)
                return child
        return EMPTY

    def code_line(self, children):
        code, words = children[0], children[1:]
        return CodeLine(
            code[0].upper(), code_number(code[1:]),
            tuple((letter, value) for letter, value, _, _ in words),
            code.column, code.end_column,
            tuple((column, end) for _, _, column, end in words),
        )

    def literal_word(self, children):
        (token,) = children
        letter, number = _split_word(token)
        return letter, float(number), token.column, token.end_column

    def expression_word(self, children):
        prefix, value = children
        letter, _ = _split_word(prefix)
        return letter, value.node, prefix.column, value.end_column

    def keyword_line(self, children):
        first, rest = children[0], children[1:]
        names, argument, argument_span, end = [first.upper()], None, None, first.end_column
        for child in rest:
            if isinstance(child, str):  # a NAME token
                names.append(child.upper())
                end = child.end_column
            else:
                argument, argument_span = child.node, (child.column, child.end_column)
        return KeywordLine(tuple(names), argument, first.column, end, argument_span)

    def assignment(self, children):
        name, value = children
        return Assignment(name[2:-1].lower(), value.node, name.column, value.end_column, (value.column, value.end_column))

    def block_line(self, children):
        label, keyword = children[0], children[1]
        count = children[2] if len(children) > 2 else None
        return BlockLine(
            _label(label), keyword.lower(), count.node if count else None, label.column,
            (count or keyword).end_column, (count.column, count.end_column) if count else None,
        )

    # --- values -----------------------------------------------------------------------------

    def number(self, children):
        (token,) = children
        return _Spanned(float(token), token.column, token.end_column)

    def parameter(self, children):
        (token,) = children
        return _Spanned(Parameter(token[2:-1].lower(), token.column, token.end_column), token.column, token.end_column)

    def group(self, children):
        opening, inner, closing = children
        return _Spanned(inner.node, opening.column, closing.end_column, inner.depth)

    def negate(self, children):
        minus, operand = children
        node = operand.node
        if type(node) is float:
            return _Spanned(-node, minus.column, operand.end_column)
        return _deeper(Negate(node, minus.column, operand.end_column), minus.column, operand.end_column, operand.depth + 1)

    def _binary(operator):  # noqa: N805 - a factory used in the class body only
        def build(self, children):
            left, right = children
            node = Binary(operator, left.node, right.node, left.column, right.end_column)
            return _deeper(node, left.column, right.end_column, max(left.depth, right.depth) + 1)

        return build

    add, subtract, multiply, divide = _binary("+"), _binary("-"), _binary("*"), _binary("/")
    del _binary


def _label(token: str) -> str:
    """'O<Loop>' → 'O<loop>', 'o100' → 'O100'."""
    return "O" + token[1:].lower()


# --- loading ---------------------------------------------------------------------------------

_PARSER: Lark | None = None


def _register_source_checkout_grammars() -> None:
    """Make ``armctl.grammars`` importable from a source checkout that was never installed."""
    try:
        importlib.import_module(GRAMMAR_PACKAGE)
        return
    except ModuleNotFoundError:
        pass
    folder = Path(__file__).resolve().parents[2] / "grammars"
    spec = importlib.util.spec_from_file_location(
        GRAMMAR_PACKAGE, folder / "__init__.py", submodule_search_locations=[str(folder)],
    )
    if spec is None or spec.loader is None or not (folder / GRAMMAR_FILE).is_file():
        raise ModuleNotFoundError(f"cannot find the grammar package {GRAMMAR_PACKAGE} (looked in {folder})")
    module = importlib.util.module_from_spec(spec)
    sys.modules[GRAMMAR_PACKAGE] = module
    spec.loader.exec_module(module)
    setattr(importlib.import_module("armctl"), "grammars", module)


def cache_path() -> str | bool:
    """Where Lark caches the built parser tables, or False for no cache.

    platformdirs' ``user_cache_dir`` (armctl/host/folders.py): ``$XDG_CACHE_HOME/armctl/`` (default
    ``~/.cache/armctl/``) on Linux, ``~/Library/Caches/armctl`` on macOS, ``%LOCALAPPDATA%\\armctl\\Cache``
    on Windows.  Building the LALR tables costs
    28 ms at every start, loading them 2.2 ms (measured here).  Built on first use rather than
    shipped in the wheel, because the tables belong to one Lark version and one Python
    (pyproject does not pin lark), so a shipped file would be stale after most installs.  The
    file starts with a hash of the grammar text, the options, Lark's and Python's versions:
    Lark rebuilds when it differs, also when the file is unreadable or corrupt, and carries on
    when it cannot write (its own ``try``; tests/test_grammar_cache.py).  In the user's own
    cache folder, not Lark's default of a shared temporary folder, since the file is a pickle."""
    from lark import __version__ as lark_version

    from ..host.folders import user_folder

    try:
        folder = user_folder("cache")
        folder.mkdir(parents=True, exist_ok=True)
    except (OSError, RuntimeError):  # RuntimeError: no home directory
        return False
    return str(folder / f"grammar-lark{lark_version}-py{sys.version_info[0]}.{sys.version_info[1]}.cache")


def parser() -> Lark:
    """The one LALR parser (built on first use, its tables cached: ``cache_path``)."""
    global _PARSER
    if _PARSER is None:
        from lark import Lark

        _register_source_checkout_grammars()
        _PARSER = Lark.open_from_package(
            GRAMMAR_PACKAGE, GRAMMAR_FILE, parser="lalr", lexer="contextual", transformer=_NodeBuilder(),
            cache=cache_path(),
        )
    return _PARSER


def parse_line(text: str) -> Node:
    """The node one source line (without its line ending) parses into.

    Raises ``LineSyntaxError`` (code, sentence, columns, hint) if it does not parse.
    """
    from lark.exceptions import UnexpectedInput

    try:
        return parser().parse(text)
    except UnexpectedInput as error:
        raise _with_suggestion(explain(error, text), text) from None


def _with_suggestion(error: LineSyntaxError, text: str) -> LineSyntaxError:
    """``error`` with "(did you mean X250?)" when a repair of the line parses (armctl/script/suggest.py)."""
    from .suggest import did_you_mean

    fix = _suggestion(text, error.column)
    if fix is None:
        return error
    return LineSyntaxError(error.message + did_you_mean(fix), error.column, error.end_column, error.hint, error.code)


@functools.lru_cache(maxsize=256)  # a script repeating one bad line repairs it once
def _suggestion(text: str, column: int):
    from lark.exceptions import UnexpectedInput

    from .statements import CODES
    from .suggest import repaired_line

    def parses(candidate: str) -> bool:
        try:
            parser().parse(candidate)
        except UnexpectedInput:
            return False
        return True

    def single_word(number: int):
        spec = CODES.get(number)
        return spec.letters[0] if spec is not None and len(spec.letters) == 1 else None

    return repaired_line(text, column, parses, single_word)
