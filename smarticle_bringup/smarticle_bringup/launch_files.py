"""ROS 2 XML launch files read without ROS: the subset the stack's launch files use, resolved to a plan.

``ros2 launch smarticle_bringup sim.launch.xml`` reads ``smarticle_bringup/launch/*.launch.xml`` on a
board with ROS 2 installed; ``smarticle-launch`` (``launcher.py``) and ``smarticle-compose``
(``compose.py``) read **the same files** here, where ``ros2 launch`` is not available from PyPI. This
module turns a file and its arguments into a ``LaunchPlan``: the nodes to start, each with its package,
executable, name, namespace, parameter files and values and remappings, in file order. It starts
nothing, imports no rclpy, and checks everything first (files, packages, executables), so a bad file
starts nothing.

The subset (ROS 2 launch XML, ``launch_xml`` / ``launch_ros`` frontends):

* ``<launch>`` root; ``<arg name default description>`` (an argument without a default is required);
  ``<let name value>``;
* ``<node pkg exec name namespace args output on_exit>`` with ``<param from="file.yaml"/>``,
  ``<param name value/>`` and ``<remap from to/>`` inside;
* ``<include file>`` with ``<arg name value/>`` inside (the included file sees only what it declares;
  an argument it does not declare is an error); ``<group>`` (scoped) with ``<push-ros-namespace
  namespace/>``;
* ``if`` / ``unless`` on every element but ``<launch>``: true for ``true``/``1``, false for
  ``false``/``0`` (any case);
* substitutions ``$(var x)``, ``$(find-pkg-share pkg)``, ``$(dirname)``, ``$(env NAME [default])`` and
  ``$(eval 'expression')`` (arithmetic, comparisons, ``and``/``or``/``not``, ``int()``, ``float()``,
  ``str()``, ``min()``, ``max()`` on numbers, strings and booleans only; nested substitutions first).

A file may include itself with changed arguments (the per-robot loop of ``sim_robots.launch.xml``);
includes deeper than ``MAX_INCLUDE_DEPTH`` are an error. Every error is a ``LaunchFileError`` whose
message is one line naming the file and line.
"""

from __future__ import annotations

import ast
import importlib.metadata
import importlib.util
import operator
import os
import shlex
import sys
from collections.abc import Callable, Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any
from xml.parsers import expat

from smarticle_common.params import ParameterError, check_params_file

from .errors import BringupError

#: How deep includes may nest (a self-including file that never stops ends here): enough for the sim
#: bridge's 200 robots.
MAX_INCLUDE_DEPTH = 256

_TRUE, _FALSE = ('true', '1'), ('false', '0')
EMPTY_YAML_STRING = "''"


class LaunchFileError(BringupError, ValueError):
    """A launch file that cannot be used: malformed XML, unknown argument, package, executable or file."""


@dataclass
class Element:
    """One XML element with its attributes, children and the line it starts on."""

    tag: str
    attrib: dict[str, str]
    line: int
    children: list[Element] = field(default_factory=list)


@dataclass(frozen=True)
class ParamFile:
    """``<param from="..."/>``: a ROS parameters file (``--params-file``)."""

    path: str


@dataclass(frozen=True)
class ParamValue:
    """``<param name value/>``: one parameter (``-p name:=value``; the value is YAML, as for ``ros2 run``)."""

    name: str
    value: str


@dataclass(frozen=True)
class NodeAction:
    """One node to start: package, executable, name, namespace, parameters and remappings, in file order."""

    package: str
    executable: str
    name: str | None
    namespace: str
    params: tuple[ParamFile | ParamValue, ...]
    remaps: tuple[tuple[str, str], ...]
    args: tuple[str, ...]
    on_exit_shutdown: bool
    where: str

    def ros_arguments(self) -> list[str]:
        """The ``--ros-args`` part of the command line (name, namespace, parameters, remappings)."""
        out = ['--ros-args']
        if self.name:
            out += ['-r', f'__node:={self.name}']
        if self.namespace not in ('', '/'):
            out += ['-r', f'__ns:={self.namespace}']
        for param in self.params:
            if isinstance(param, ParamFile):
                out += ['--params-file', param.path]
            else:   # the value is YAML, as for ros2 run; an empty value is the empty string
                out += ['-p', f'{param.name}:={param.value or EMPTY_YAML_STRING}']
        for source, target in self.remaps:
            out += ['-r', f'{source}:={target}']
        return out

    def command_arguments(self) -> list[str]:
        """Everything after the executable: ``args`` then the ``--ros-args`` part."""
        return [*self.args, *self.ros_arguments()]

    @property
    def full_name(self) -> str:
        """Fully qualified node name (the executable stands in for a node without a name)."""
        ns = self.namespace.rstrip('/')
        return f'{ns}/{self.name or self.executable}'


@dataclass(frozen=True)
class LaunchPlan:
    """A resolved launch file: its nodes in order, and the arguments it was given (defaults filled in)."""

    path: Path
    arguments: dict[str, str]
    nodes: tuple[NodeAction, ...]


# ---------------------------------------------------------------------------------------------- XML
def parse_xml(path: Path) -> Element:
    """Read ``path`` into Elements with line numbers (LaunchFileError for malformed XML)."""
    try:
        data = path.read_bytes()
    except OSError as err:
        raise LaunchFileError(f'{path}: cannot read the launch file ({err.strerror})') from None
    parser = expat.ParserCreate()
    stack: list[Element] = []
    roots: list[Element] = []

    def start(tag: str, attrib: dict[str, str]) -> None:
        element = Element(tag, dict(attrib), parser.CurrentLineNumber)
        (stack[-1].children if stack else roots).append(element)
        stack.append(element)

    def end(_tag: str) -> None:
        stack.pop()

    parser.StartElementHandler = start
    parser.EndElementHandler = end
    try:
        parser.Parse(data, True)
    except expat.ExpatError as err:
        raise LaunchFileError(f'{path}:{err.lineno}: malformed XML: {expat.ErrorString(err.code)}') from None
    return roots[0]


# ---------------------------------------------------------------------------------------------- packages
def package_share(package: str) -> Path:
    """The share folder of ``package``: installed (ament index, ``<prefix>/share``) or the source checkout.

    Looked up in order: ``AMENT_PREFIX_PATH`` (a sourced colcon or apt install), the Python environment's
    ``share/<package>`` (a pip install of the package's data files), then the package's source folder
    (the folder with its ``package.xml`` next to the Python package, as in an editable install): all three
    hold ``package.xml``, ``launch/`` and ``config/`` the same way.
    """
    prefixes = [p for p in os.environ.get('AMENT_PREFIX_PATH', '').split(os.pathsep) if p] + [sys.prefix]
    for prefix in prefixes:
        share = Path(prefix) / 'share' / package
        if (share / 'package.xml').is_file():
            return share
    spec = importlib.util.find_spec(package) if package.isidentifier() else None
    if spec is not None and spec.submodule_search_locations:
        for location in spec.submodule_search_locations:
            folder = Path(location).resolve().parent
            if (folder / 'package.xml').is_file():
                return folder
    raise LaunchFileError(f'unknown package {package!r}: no share/{package}/package.xml on AMENT_PREFIX_PATH '
                          'or in this Python environment')


def package_executables(package: str) -> set[str]:
    """The executables (console scripts) that ``package`` installs; LaunchFileError if it is unknown."""
    try:
        dist = importlib.metadata.distribution(package)
    except importlib.metadata.PackageNotFoundError:
        raise LaunchFileError(f'unknown package {package!r}: it is not installed in this Python environment'
                              ) from None
    return {ep.name for ep in dist.entry_points if ep.group == 'console_scripts'}


# ---------------------------------------------------------------------------------------------- substitutions
_EVAL_BINARY: dict[type, Callable[[Any, Any], Any]] = {
    ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul, ast.Div: operator.truediv,
    ast.FloorDiv: operator.floordiv, ast.Mod: operator.mod}
_EVAL_COMPARE: dict[type, Callable[[Any, Any], Any]] = {
    ast.Eq: operator.eq, ast.NotEq: operator.ne, ast.Lt: operator.lt, ast.LtE: operator.le,
    ast.Gt: operator.gt, ast.GtE: operator.ge, ast.In: lambda a, b: operator.contains(b, a),
    ast.NotIn: lambda a, b: not operator.contains(b, a)}
_EVAL_CALLS: dict[str, Callable[..., Any]] = {'int': int, 'float': float, 'str': str, 'min': min, 'max': max,
                                              'abs': abs}
#: String methods ``$(eval)`` may call (to split a ``package/executable`` or a ``0,2`` list argument).
_EVAL_METHODS = {'split', 'strip', 'lower', 'replace'}


def evaluate(expression: str) -> str:
    """``$(eval ...)``: a small Python expression of numbers, strings and booleans; the result as text.

    Strings may be split (``'a/b'.split('/')[0]``, ``'1' in '0,1'.split(',')``), stripped and lowered; the
    result must be a number, a string or a boolean.
    """
    def walk(node: ast.AST) -> Any:
        if isinstance(node, ast.Expression):
            return walk(node.body)
        if isinstance(node, ast.Constant) and isinstance(node.value, (int, float, str, bool)):
            return node.value
        if isinstance(node, ast.Name) and node.id in ('True', 'False'):
            return node.id == 'True'
        if isinstance(node, ast.BinOp) and type(node.op) in _EVAL_BINARY:
            return _EVAL_BINARY[type(node.op)](walk(node.left), walk(node.right))
        if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.Not, ast.USub, ast.UAdd)):
            value = walk(node.operand)
            return (not value) if isinstance(node.op, ast.Not) else (-value if isinstance(node.op, ast.USub)
                                                                      else +value)
        if isinstance(node, ast.BoolOp):
            values = [walk(v) for v in node.values]
            return all(values) if isinstance(node.op, ast.And) else any(values)
        if isinstance(node, ast.Compare):
            left = walk(node.left)
            for op, right_node in zip(node.ops, node.comparators, strict=True):
                if type(op) not in _EVAL_COMPARE:
                    raise ValueError(f'operator {type(op).__name__} is not supported')
                right = walk(right_node)
                if not _EVAL_COMPARE[type(op)](left, right):
                    return False
                left = right
            return True
        if isinstance(node, ast.IfExp):
            return walk(node.body) if walk(node.test) else walk(node.orelse)
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name) and node.func.id in _EVAL_CALLS
                and not node.keywords):
            return _EVAL_CALLS[node.func.id](*(walk(a) for a in node.args))
        if (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute) and node.func.attr in _EVAL_METHODS
                and not node.keywords):
            target = walk(node.func.value)
            if not isinstance(target, str):
                raise ValueError(f'.{node.func.attr}() applies to strings only')
            return getattr(target, node.func.attr)(*(walk(a) for a in node.args))
        if isinstance(node, ast.Subscript):
            sequence, index = walk(node.value), walk(node.slice)
            if not isinstance(sequence, (str, list)) or isinstance(index, bool) or not isinstance(index, int):
                raise ValueError('only a string or a split string may be indexed, by an integer')
            return sequence[index]
        raise ValueError(f'{type(node).__name__} is not supported in $(eval)')
    try:
        result = walk(ast.parse(expression.strip(), mode='eval'))
        if not isinstance(result, (int, float, str, bool)):
            raise ValueError(f'the result must be a number, a string or a boolean, not {type(result).__name__}')
        return str(result)
    except (SyntaxError, ValueError, TypeError, ZeroDivisionError, IndexError) as err:
        raise ValueError(f'$(eval {expression!r}): {err}') from None


def _split_substitution(body: str) -> list[str]:
    """Split the inside of ``$(...)`` into words; single-quoted words keep their spaces."""
    try:
        return shlex.split(body, posix=True)
    except ValueError as err:
        raise ValueError(f'$({body}): {err}') from None


def _matching(text: str, start: int) -> int:
    """Index of the ``)`` closing the ``$(`` at ``start`` (nested ``$(...)`` and quotes skipped)."""
    depth, i, quote = 0, start, ''
    while i < len(text):
        c = text[i]
        if quote:
            if c == quote:
                quote = ''
        elif c == "'" and depth >= 1:
            quote = c
        elif text.startswith('$(', i):
            depth += 1
            i += 1
        elif c == '(':
            depth += 1
        elif c == ')':
            depth -= 1
            if depth == 0:
                return i
        i += 1
    raise ValueError(f'unclosed substitution in {text!r}')


@dataclass
class Scope:
    """The launch configurations visible to an element, the file it is in and the pushed namespace."""

    values: dict[str, str]
    path: Path
    namespace: str = ''
    depth: int = 0
    #: The names ``$(var)`` has resolved, in order (which arguments an expression used).
    used: list[str] = field(default_factory=list)

    def child(self) -> Scope:
        """A copy for a ``<group>``: what it sets does not leak out."""
        return Scope(dict(self.values), self.path, self.namespace, self.depth)

    def substitute(self, text: str) -> str:
        """Resolve every ``$(...)`` in ``text`` (ValueError says which one failed)."""
        out, i = [], 0
        while True:
            j = text.find('$(', i)
            if j < 0:
                out.append(text[i:])
                return ''.join(out)
            out.append(text[i:j])
            end = _matching(text, j)
            raw = text[j + 2:end]
            out.append(self._eval(raw) if raw.split(None, 1)[:1] == ['eval'] else self._one(self.substitute(raw)))
            i = end + 1

    def _eval(self, raw: str) -> str:
        """``$(eval ...)`` whose text is ``raw``; if it fails, the ValueError names the argument whose value
        broke it (the one that, set to 1, makes the expression work)."""
        first = len(self.used)
        try:
            return self._one(self.substitute(raw))
        except ValueError as err:
            for name in dict.fromkeys(self.used[first:]):
                trial = Scope({**self.values, name: '1'}, self.path, self.namespace, self.depth)
                try:
                    trial._one(trial.substitute(raw))
                except ValueError:
                    continue
                raise ValueError(f'argument {name} has a value this file cannot use, {self.values[name]!r} '
                                 f'({err})') from None
            raise

    def _one(self, body: str) -> str:
        if body.split(None, 1)[:1] == ['eval']:
            expression = body[len('eval'):].strip()
            if len(expression) >= 2 and expression[0] == expression[-1] and expression[0] in '\'"':
                expression = expression[1:-1]           # the one pair of quotes around the expression
            return evaluate(expression)
        words = _split_substitution(body)
        if not words:
            raise ValueError('empty substitution $()')
        kind, rest = words[0], words[1:]
        if kind == 'var' and len(rest) == 1:
            if rest[0] not in self.values:
                raise ValueError(f'$(var {rest[0]}): no argument or let of that name')
            self.used.append(rest[0])
            return self.values[rest[0]]
        if kind == 'find-pkg-share' and len(rest) == 1:
            try:
                return str(package_share(rest[0]))
            except LaunchFileError as err:
                raise ValueError(str(err)) from None
        if kind == 'dirname' and not rest:
            return str(self.path.parent)
        if kind == 'env' and len(rest) in (1, 2):
            if rest[0] in os.environ:
                return os.environ[rest[0]]
            if len(rest) == 2:
                return rest[1]
            raise ValueError(f'$(env {rest[0]}): not set and no default given')
        raise ValueError(f'unsupported substitution $({body})')


# ---------------------------------------------------------------------------------------------- the reader
_ATTRIBUTES: dict[str, set[str]] = {
    'launch': {'version'},
    'arg': {'name', 'default', 'description', 'value'},
    'let': {'name', 'value'},
    'node': {'pkg', 'exec', 'name', 'namespace', 'args', 'output', 'on_exit'},
    'param': {'from', 'name', 'value'},
    'remap': {'from', 'to'},
    'include': {'file'},
    'group': {'scoped'},
    'push-ros-namespace': {'namespace'},
}
_CONDITIONS = {'if', 'unless'}


class _Reader:
    """Walks launch files into NodeActions (one instance per ``resolve`` call)."""

    def __init__(self, check_executables: bool) -> None:
        self.nodes: list[NodeAction] = []
        self.check_executables = check_executables
        self._executables: dict[str, set[str]] = {}
        self._parsed: dict[Path, Element] = {}

    def fail(self, scope: Scope, element: Element, message: str) -> LaunchFileError:
        return LaunchFileError(f'{scope.path}:{element.line}: {message}')

    def sub(self, scope: Scope, element: Element, text: str) -> str:
        try:
            return scope.substitute(text)
        except ValueError as err:
            raise self.fail(scope, element, str(err)) from None

    def attr(self, scope: Scope, element: Element, name: str, required: bool = True) -> str | None:
        if name not in element.attrib:
            if required:
                raise self.fail(scope, element, f'<{element.tag}> needs the attribute {name!r}')
            return None
        return self.sub(scope, element, element.attrib[name])

    def check_attributes(self, scope: Scope, element: Element, allowed: set[str]) -> None:
        unknown = set(element.attrib) - allowed - _CONDITIONS
        if unknown:
            raise self.fail(scope, element, f'<{element.tag}>: unsupported attribute(s) {", ".join(sorted(unknown))}'
                            f' (supported: {", ".join(sorted(allowed | _CONDITIONS))})')

    def active(self, scope: Scope, element: Element) -> bool:
        """The element's ``if`` / ``unless`` condition (true without one)."""
        for key, want in (('if', True), ('unless', False)):
            if key in element.attrib:
                value = self.sub(scope, element, element.attrib[key]).strip().lower()
                if value not in _TRUE + _FALSE:
                    raise self.fail(scope, element, f'{key}="{element.attrib[key]}" gives {value!r}; a condition '
                                    "must be 'true', 'false', '1' or '0'")
                if (value in _TRUE) != want:
                    return False
        return True

    # ------------------------------------------------------------------ files
    def read_file(self, path: Path, given: Mapping[str, str], depth: int, where: str,
                  namespace: str = '') -> dict[str, str]:
        """Read one launch file with the arguments ``given`` (inside ``namespace``); return its argument values."""
        if depth > MAX_INCLUDE_DEPTH:
            raise LaunchFileError(f'{where}: includes nest deeper than {MAX_INCLUDE_DEPTH} (a file that '
                                  'includes itself without an end?)')
        if not path.is_file():
            raise LaunchFileError(f'{where}: launch file {path} does not exist')
        if path not in self._parsed:
            self._parsed[path] = parse_xml(path)
        root = self._parsed[path]
        scope = Scope({}, path, namespace, depth)
        if root.tag != 'launch':
            raise self.fail(scope, root, f'the root element is <{root.tag}>, not <launch>')
        self.check_attributes(scope, root, _ATTRIBUTES['launch'])
        declared = [child for child in root.children if child.tag == 'arg']
        names = {child.attrib.get('name', '') for child in declared}
        unknown = sorted(set(given) - names)
        if unknown:
            raise LaunchFileError(f'{where}: unknown argument(s) {", ".join(unknown)} for {path.name}; it declares: '
                                  f'{", ".join(sorted(n for n in names if n)) or "none"}')
        scope.values.update(given)
        self.walk(scope, root.children, top=True)
        return {name: scope.values[name] for name in names if name in scope.values}

    def walk(self, scope: Scope, elements: list[Element], top: bool = False) -> None:
        for element in elements:
            handler = getattr(self, 'do_' + element.tag.replace('-', '_'), None)
            if handler is None or element.tag in ('param', 'remap'):
                raise self.fail(scope, element, f'unsupported element <{element.tag}> here (supported: arg, let, '
                                'node, include, group, push-ros-namespace)')
            if element.tag == 'arg' and not top:
                raise self.fail(scope, element, '<arg> declares a launch argument at the top of a file only')
            self.check_attributes(scope, element, _ATTRIBUTES[element.tag])
            if element.tag != 'arg' and not self.active(scope, element):
                continue
            handler(scope, element)

    # ------------------------------------------------------------------ elements
    def do_arg(self, scope: Scope, element: Element) -> None:
        name = self.attr(scope, element, 'name')
        assert name is not None
        if 'value' in element.attrib:
            raise self.fail(scope, element, '<arg value=...> belongs inside <include>; declare with default=')
        if name in scope.values:
            return                      # given by the command line or the including file
        if 'default' not in element.attrib:
            raise self.fail(scope, element, f'argument {name!r} is required (it has no default): give {name}:=VALUE')
        scope.values[name] = self.sub(scope, element, element.attrib['default'])

    def do_let(self, scope: Scope, element: Element) -> None:
        name, value = self.attr(scope, element, 'name'), self.attr(scope, element, 'value')
        assert name is not None and value is not None
        scope.values[name] = value

    def do_group(self, scope: Scope, element: Element) -> None:
        scoped = element.attrib.get('scoped', 'true').lower() not in _FALSE
        self.walk(scope.child() if scoped else scope, element.children)

    def do_push_ros_namespace(self, scope: Scope, element: Element) -> None:
        namespace = self.attr(scope, element, 'namespace')
        assert namespace is not None
        scope.namespace = join_namespace(scope.namespace, namespace)

    def do_include(self, scope: Scope, element: Element) -> None:
        target = self.attr(scope, element, 'file')
        assert target is not None
        given: dict[str, str] = {}
        for child in element.children:
            if child.tag != 'arg':
                raise self.fail(scope, child, f'<include> holds <arg name value/> only, not <{child.tag}>')
            self.check_attributes(scope, child, {'name', 'value'})
            name, value = self.attr(scope, child, 'name'), self.attr(scope, child, 'value')
            assert name is not None and value is not None
            given[name] = value
        path = Path(target)
        if not path.is_absolute():
            path = scope.path.parent / path
        self.read_file(path, given, scope.depth + 1, f'{scope.path}:{element.line}', scope.namespace)

    def do_node(self, scope: Scope, element: Element) -> None:
        package, executable = self.attr(scope, element, 'pkg'), self.attr(scope, element, 'exec')
        assert package is not None and executable is not None
        if self.check_executables:
            if package not in self._executables:
                try:
                    self._executables[package] = package_executables(package)
                except LaunchFileError as err:
                    raise self.fail(scope, element, str(err)) from None
            if executable not in self._executables[package]:
                raise self.fail(scope, element, f'package {package!r} has no executable {executable!r} (it has: '
                                f'{", ".join(sorted(self._executables[package])) or "none"})')
        name = self.attr(scope, element, 'name', required=False)
        namespace = self.attr(scope, element, 'namespace', required=False) or ''
        namespace = namespace if namespace.startswith('/') else join_namespace(scope.namespace, namespace)
        on_exit = self.attr(scope, element, 'on_exit', required=False)
        if on_exit not in (None, 'shutdown'):
            raise self.fail(scope, element, f'on_exit="{on_exit}": only "shutdown" is supported')
        text = self.attr(scope, element, 'args', required=False) or ''
        try:
            args = tuple(shlex.split(text))
        except ValueError as err:     # an argument's value with an unmatched quote
            raise self.fail(scope, element, f'args="{text}": {err}') from None
        params: list[ParamFile | ParamValue] = []
        remaps: list[tuple[str, str]] = []
        for child in element.children:
            if child.tag not in ('param', 'remap'):
                raise self.fail(scope, child, f'<node> holds <param> and <remap> only, not <{child.tag}>')
            self.check_attributes(scope, child, _ATTRIBUTES[child.tag])
            if not self.active(scope, child):
                continue
            if child.tag == 'remap':
                source, target = self.attr(scope, child, 'from'), self.attr(scope, child, 'to')
                assert source is not None and target is not None
                remaps.append((source, target))
            elif 'from' in child.attrib:
                path = Path(self.attr(scope, child, 'from') or '')
                path = path.absolute()  # a relative path is the caller's, from the working folder, as ros2 launch
                if not path.is_file():
                    raise self.fail(scope, child, f'parameter file {path} does not exist')
                try:
                    check_params_file(str(path))
                except ParameterError as err:
                    raise self.fail(scope, child, str(err)) from None
                params.append(ParamFile(str(path)))
            else:
                pname, value = self.attr(scope, child, 'name'), self.attr(scope, child, 'value')
                assert pname is not None and value is not None
                params.append(ParamValue(pname, value))
        self.nodes.append(NodeAction(package, executable, name or None, namespace or '/', tuple(params),
                                     tuple(remaps), args, on_exit == 'shutdown',
                                     f'{scope.path}:{element.line}'))


def join_namespace(outer: str, inner: str) -> str:
    """``outer`` + ``inner`` as an absolute namespace (an absolute ``inner`` replaces ``outer``)."""
    if inner.startswith('/'):
        return '/' + inner.strip('/') if inner.strip('/') else '/'
    parts = [p for p in (outer.strip('/'), inner.strip('/')) if p]
    return '/' + '/'.join(parts) if parts else ''


def parse_arguments(items: list[str]) -> dict[str, str]:
    """``name:=value`` words of a command line as a dict (LaunchFileError for anything else)."""
    out: dict[str, str] = {}
    for item in items:
        name, sep, value = item.partition(':=')
        if not sep or not name:
            raise LaunchFileError(f'launch argument {item!r} is not of the form name:=value')
        out[name] = value
    return out


def resolve(path: str | Path, arguments: Mapping[str, str] | None = None,
            check_executables: bool = True) -> LaunchPlan:
    """Read launch file ``path`` with ``arguments``; return the plan (LaunchFileError, one line, if bad).

    ``check_executables`` also checks that every node's package is installed and has its executable.
    """
    path = Path(path).resolve()
    reader = _Reader(check_executables)
    limit = sys.getrecursionlimit()
    sys.setrecursionlimit(max(limit, 12 * MAX_INCLUDE_DEPTH + 1000))   # a few frames per include level
    try:
        values = reader.read_file(path, dict(arguments or {}), 0, str(path))
    finally:
        sys.setrecursionlimit(limit)
    return LaunchPlan(path, values, tuple(reader.nodes))


def find_launch_file(package: str, name: str) -> Path:
    """``ros2 launch PACKAGE NAME``: the file ``NAME`` in the package's ``launch/`` folder."""
    path = package_share(package) / 'launch' / name
    if not path.is_file():
        raise LaunchFileError(f'package {package!r} has no launch file {name!r} (looked in {path.parent})')
    return path


def plan_from_command_line(words: list[str]) -> LaunchPlan:
    """``[PACKAGE] FILE [name:=value ...]`` as a checked plan (LaunchFileError if anything is wrong)."""
    if not words:
        raise LaunchFileError('give a launch file, or a package and a launch file name, then name:=value arguments')
    if words[0].endswith('.xml') or Path(words[0]).is_file() or len(words) == 1 or ':=' in words[1]:
        path, rest = Path(words[0]), words[1:]
    else:
        path, rest = find_launch_file(words[0], words[1]), words[2:]
    return resolve(path, parse_arguments(rest))
