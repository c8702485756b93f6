"""Bad models: for each, every diagnostic's exact line, column, message,
hint and note. The table gives the model text, then the expected
diagnostics in the order ``Diagnostics.sorted()`` gives them.

``{dir}`` in an expected message stands for the folder of the model file.
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path
from textwrap import dedent

import pytest

from easylab.pipeline import check_file
from easylab.frontend.loader import library_path


@dataclass(frozen=True)
class E:
    """One expected diagnostic; ``note`` is (line, col, message[, file])."""

    line: int
    col: int
    message: str
    hint: str | None = None
    note: tuple | None = None


def _std_position(declaration: str) -> tuple[int, int]:
    """(line, column) of the name a declaration of the shipped std.elab declares."""
    for number, line in enumerate(library_path("std").read_text(encoding="utf-8").splitlines(), 1):
        if line.startswith(declaration):
            return number, len(declaration) - len(declaration.split()[-1]) + 1
    raise LookupError(declaration)


def case(name: str, text: str, *expected: E, files: dict[str, str] | None = None):
    return pytest.param(text, expected, files or {}, id=name)


CASES = [
    case('syntax-missing-arrow', dedent("""\
        dataflow D {
            c = Const<int16>(value = 1)
            c.y temperature
        }
        """),
         E(3, 9, "unexpected 'temperature': an edge needs '->' between its source and its destination")),
    case('syntax-missing-arrow-first', 'dataflow D { a.y b.x }\n',
         E(1, 18, "unexpected 'b': an edge needs '->' between its source and its destination")),
    case('syntax-missing-type', 'var speed = 10\n',
         E(1, 11, "unexpected '=': a declaration needs ':' and a type, as in 'var speed: int16'")),
    case('syntax-missing-type-after-colon', 'param p: = 3\n',
         E(1, 10, "unexpected '=': a declaration needs ':' and a type, as in 'var speed: int16'")),
    case('syntax-unclosed-inline-c', dedent("""\
        actor type A() {
            out y: int8
            step {{ if (1) { y = 1; }}
        }
        """),
         E(3, 10, "inline C block '{{' is never closed by a balancing '}}'",
           hint='braces inside inline C, in its strings and comments too, must balance')),
    case('syntax-unexpected-character', 'var x: int8 = 1 $\n',
         E(1, 17, "unexpected character '$'")),
    case('syntax-unexpected-eof', dedent("""\
        dataflow D {
            a.y -> b.x
        """),
         E(2, 15, "unexpected end of the file, expected a name, 'delay', '}'")),
    case('syntax-duplicate-attribute', 'param p: int16 = 1 unit "ms" range 0..10 unit "s"\n',
         E(1, 42, "attribute 'unit' given twice", hint='each attribute may appear at most once')),
    case('syntax-duplicate-service', 'var v: int16 service ro service rw\n',
         E(1, 25, "attribute 'service' given twice", hint='each attribute may appear at most once')),
    case('syntax-misspelt-keyword', dedent("""\
        var x: int8
        vra y: int8
        """),
         E(2, 1, "unexpected 'vra', expected a declaration (model, import, const, param, var, channel, device, "
                 'actor, dataflow, chart, task, debug, modbus)',
           hint="did you mean 'var'?")),
    case('syntax-edge-outside-dataflow', dedent("""\
        var x: int8
        x -> y
        """),
         E(2, 1, "unexpected 'x': edges and actor instances belong inside a 'dataflow { ... }'")),
    case('syntax-equals-in-guard', dedent("""\
        var x: int8
        chart C {
            initial step A { }
            transition A -> A when x = 1
        }
        """),
         E(4, 30, "unexpected '=': compare with '==': '=' only assigns")),
    case('syntax-initial-value-after-attributes', 'param p: int16 range 0..10 = 5\n',
         E(1, 28, "unexpected '=': the initial value '= ...' comes right after the type, before the attributes")),
    case('syntax-transition-without-guard', dedent("""\
        chart C {
            initial step A { }
            transition A -> A
        }
        """),
         E(4, 1, "unexpected '}': a transition needs 'when' and a guard, as in 'transition A -> B when go'")),
    case('syntax-unclosed-comment', dedent("""\
        var x: int8
        /* a comment
        var y: int8
        """),
         E(2, 1, "comment '/*' is never closed by '*/'")),
    case('syntax-unclosed-string', 'model m "EasyLab\n',
         E(1, 9, 'string is never closed: a string ends with \'"\' on the same line')),
    case('syntax-unknown-escape', 'model m "a\\qb"\n',
         E(1, 11, "unknown escape '\\q' in a string", hint='the escapes are \\n \\t \\r \\0 \\" and \\\\')),
    case('syntax-two-model-headers', dedent("""\
        model a
        model b
        """),
         E(2, 1, "a file has at most one 'model' header", note=(1, 1, "the first 'model' header"))),
    case('syntax-two-drivers', dedent("""\
        device type D() {
            driver "a"
            driver "b"
        }
        """),
         E(3, 5, "a device type has at most one 'driver'")),
    case('syntax-number-too-long', dedent("""\
        const C: int32 = 123456789012345678901234567890123456789012345
        """),
         E(1, 18, "number '12345678901234567890...' is too long for any type")),
    case('import-missing-file', 'import "lib/missing.elab"\n',
         E(1, 1, "imported file 'lib/missing.elab' not found (looked at {dir}/lib/missing.elab)")),
    case('import-unknown-library', 'import stdd\n',
         E(1, 1, "unknown library 'stdd'", hint="did you mean 'std'?")),
    case('import-unknown-library-no-match', 'import robots\n',
         E(1, 1, "unknown library 'robots'", hint='import a file by its path in quotes: import "lib/actors.elab"')),
    case('name-unknown-var-in-edge', dedent("""\
        import std
        var temperature: int16
        dataflow D {
            c = Const<int16>(value = 1)
            c.y -> temprature
        }
        """),
         E(5, 12, "unknown name 'temprature' in dataflow 'D'", hint="did you mean 'temperature'?")),
    case('name-unknown-actor-type', dedent("""\
        import std
        var v: int16
        dataflow D {
            c = Cnst<int16>(value = 1)
            c.y -> v
        }
        """),
         E(4, 9, "unknown actor type 'Cnst'", hint="did you mean 'Const'?")),
    case('name-unknown-type', 'var x: unit16\n',
         E(1, 8, "unknown type 'unit16'", hint="did you mean 'uint16'?")),
    case('name-unknown-step', dedent("""\
        chart C {
            initial step Idle { }
            transition Idle -> Idel when true
        }
        """),
         E(3, 24, "chart 'C' has no step 'Idel'", hint="did you mean 'Idle'?")),
    case('name-unknown-port', dedent("""\
        import std
        var v: int16
        dataflow D {
            c = Const<int16>(value = 1)
            c.out -> v
        }
        """),
         E(5, 7, "actor 'c' (Const) has no port 'out'", hint='its ports: y')),
    case('name-unknown-in-guard', dedent("""\
        var start_cmd: bool
        chart C {
            initial step A { }
            transition A -> A when start_cmnd
        }
        """),
         E(4, 28, "unknown name 'start_cmnd'", hint="did you mean 'start_cmd'?")),
    case('name-duplicate', dedent("""\
        var speed: int16
        param speed: int16
        """),
         E(2, 7, "'speed' is already declared as a var",
           hint='give one of them another name',
           note=(1, 5, "'speed' is first declared here"))),
    case('name-duplicate-with-import', dedent("""\
        import std
        var Add: int16
        """),
         E(2, 5, "'Add' is already declared as an actor type",
           hint='give one of them another name',
           note=(*_std_position("actor type Add"), "'Add' is first declared here", "<std>"))),
    case('name-wrong-kind', dedent("""\
        var v: int16
        task t period 1 ms { run v }
        """),
         E(2, 26, "'v' is a var, not a dataflow or chart", note=(1, 5, "'v' is declared here"))),
    case('name-var-in-const', dedent("""\
        var x: int16
        const C: int16 = x
        """),
         E(2, 18, "'x' is a var, known only at run time; a compile-time constant is needed here",
           hint='use literals and consts here')),
    case('type-edge-mismatch', dedent("""\
        import std
        var small: int8
        dataflow D {
            c = Const<int16>(value = 1)
            c.y -> small
        }
        """),
         E(5, 5, "type mismatch: 'c.y' is 'int16' but 'small' is 'int8'", hint='convert with Cast<int16, int8>()')),
    case('type-actor-argument', dedent("""\
        import std
        param th: uint16 = 100
        var b: bool
        dataflow D {
            cmp = Compare<int16>(op = ">", threshold = th)
            cmp.y -> b
        }
        """),
         E(5, 48, "parameter 'threshold' of 'cmp' expects 'int16' but the value is 'uint16'",
           hint="an argument is not converted: declare the param or const it names as 'int16', or give the actor "
                "the type argument that takes 'uint16'")),
    case('type-edge-bool-to-int', dedent("""\
        import std
        var v: int16
        var b: bool
        dataflow D {
            b -> v
        }
        """),
         E(5, 5, "type mismatch: 'b' is 'bool' but 'v' is 'int16'")),
    case('type-guard-not-bool', dedent("""\
        var x: int16
        chart C {
            initial step A { }
            transition A -> A when x + 1
        }
        """),
         E(4, 28, "a transition guard must be a bool, not 'int16'", hint='compare it, e.g. x > 0')),
    case('type-bound-violation', dedent("""\
        import std
        var v: float32
        dataflow D {
            m = MovingAverage<float32>(n = 4)
            v -> m.x
            m.y -> v
        }
        """),
         E(4, 23, "'float32' is not an integer type, as 'MovingAverage' requires of T",
           hint='T must be any integer type')),
    case('type-inference-fails', dedent("""\
        import std
        var big: uint32
        var small: int8
        dataflow D {
            s = Add()
            big -> s.a
            small -> s.b
            s.y -> small
        }
        """),
         E(5, 9, "cannot infer type argument T of 'Add' from what 's' is connected to",
           hint='give it explicitly: s = Add<int16>(...)')),
    case('type-inference-no-edges', dedent("""\
        import std
        dataflow D {
            c = Const(value = 1)
        }
        """),
         E(3, 9, "cannot infer type argument T of 'Const' from what 'c' is connected to",
           hint='give it explicitly: c = Const<int16>(...)')),
    case('type-wrong-type-arg-count', dedent("""\
        import std
        var v: int16
        dataflow D {
            c = Cast<int16>()
            v -> c.x
            c.y -> v
        }
        """),
         E(4, 9, "actor type 'Cast' takes 2 type argument(s), 1 given")),
    case('type-action-value', dedent("""\
        var v: int8
        chart C {
            initial step A { entry v = 300 }
        }
        """),
         E(3, 32, "the value assigned to 'v': 300 does not fit 'int8' (-128..127)")),
    case('const-overflow-literal', 'const C: int8 = 200\n',
         E(1, 17, "const 'C': 200 does not fit 'int8' (-128..127)")),
    case('const-overflow-typed', dedent("""\
        const A: int8 = 100
        const B: int8 = A + A
        """),
         E(2, 17, "constant 200 overflows 'int8' (-128..127)")),
    case('const-division-by-zero', 'const C: int16 = 10 / (5 - 5)\n',
         E(1, 24, 'division by zero in a constant expression')),
    case('const-cycle', dedent("""\
        const A: int16 = B + 1
        const B: int16 = A
        """),
         E(1, 7, "const 'A' is defined in terms of itself (A -> B -> A)")),
    case('const-self', 'const A: int16 = A\n',
         E(1, 7, "const 'A' is defined in terms of itself")),
    case('const-float-range', 'var f: float32 = 1e300\n',
         E(1, 18, "the initial value of var 'f': 1e+300 is beyond the range of 'float32'")),
    case('data-default-out-of-range', 'param p: int16 = 5 range 10..20\n',
         E(1, 18, "the initial value 5 of 'p' is outside its range 10..20")),
    case('data-no-default-out-of-range', 'param p: int16 range 10..20\n',
         E(1, 7, "the initial value 0 of 'p' is outside its range 10..20",
           hint='give an initial value inside the range')),
    case('data-empty-range', 'param p: int16 = 15 range 20..10\n',
         E(1, 21, 'empty range: 20 is above 10')),
    case('data-time-needs-unit', 'param t: time = 5\n',
         E(1, 17, "the initial value of param 't' is a 'time': write a duration such as '5 ms'")),
    case('data-persist-on-var', 'var v: int16 persist\n',
         E(1, 14, "only params can be 'persist'", hint="make it a param, or drop 'persist'")),
    case('data-array-var', 'var v: int16[4]\n',
         E(1, 8, 'a var is a scalar; arrays are for actor state only')),
    case('write-param-by-dataflow', dedent("""\
        import std
        param p: int16
        dataflow D {
            c = Const<int16>(value = 1)
            c.y -> p
        }
        """),
         E(5, 12, "param 'p' cannot be written by a dataflow",
           hint='params are written only through the debug and service interfaces; use a var')),
    case('write-param-by-chart', dedent("""\
        param p: bool
        chart C {
            initial step A { entry p = true }
        }
        """),
         E(3, 28, "param 'p' cannot be assigned by a chart",
           hint='params are written only through the debug and service interfaces; use a var')),
    case('write-var-two-tasks', dedent("""\
        import std
        var v: int16
        dataflow D1 {
            c = Const<int16>(value = 1)
            c.y -> v
        }
        chart C {
            initial step A { entry v = 2 }
        }
        task t1 period 1 ms { run D1 }
        task t2 period 2 ms { run C }
        """),
         E(8, 22, "var 'v' is written by task 't2' and by task 't1'",
           hint='each var and device input has one writing task; pass data between tasks through a channel',
           note=(5, 5, "written in task 't1' here"))),
    case('write-var-twice-in-dataflow', dedent("""\
        import std
        var v: int16
        dataflow D {
            c = Const<int16>(value = 1)
            c.y -> v
            c.y -> v
        }
        """),
         E(6, 12, "'v' is written twice in dataflow 'D'", note=(5, 5, 'the other edge'))),
    case('write-device-output', dedent("""\
        import std
        device button: DigitalIn(pin = "PD2")
        chart C {
            initial step A { entry button.level = true }
        }
        """),
         E(4, 28, "'button.level' is a device output; only device inputs can be assigned")),
    case('claim-two-devices', dedent("""\
        import std
        device a: AnalogIn(channel = 1)
        device b: AnalogIn(channel = 1)
        """),
         E(3, 1, "resource adc[1] is claimed by device 'b' and by device 'a'",
           hint='each resource has one owner; choose another pin, channel or UART',
           note=(2, 1, "claimed by device 'a' here"))),
    case('claim-device-and-composed-device', dedent("""\
        import std
        device a: AnalogIn(channel = 0)
        device t: Pt100(channel = 0)
        """),
         E(3, 1, "resource adc[0] is claimed by device 't.adc' and by device 'a'",
           hint='each resource has one owner; choose another pin, channel or UART',
           note=(2, 1, "claimed by device 'a' here"))),
    case('claim-device-and-interface', dedent("""\
        device type Serial() {
            claims uart[1]
            out byte: uint8
            driver "serial"
        }
        device s: Serial()
        modbus rtu on uart1
        """),
         E(7, 15, "resource uart[1] is claimed by interface 'modbus rtu' and by device 's'",
           hint='each resource has one owner; choose another pin, channel or UART',
           note=(6, 1, "claimed by device 's' here"))),
    case('claim-two-interfaces-one-uart', dedent("""\
        debug on uart0
        modbus rtu on uart0
        """),
         E(2, 15, "resource uart[0] is claimed by interface 'modbus rtu' and by interface 'debug'",
           hint='each resource has one owner; choose another pin, channel or UART',
           note=(1, 10, "claimed by interface 'debug' here"))),
    case('iface-twice', dedent("""\
        debug on uart0
        debug on uart1
        """),
         E(2, 1, 'a model has at most one debug interface', note=(1, 1, 'the other one'))),
    case('iface-not-uart', 'debug on adc3\n',
         E(1, 10, "the debug interface runs on a UART, not on 'adc[3]'")),
    case('iface-bad-setting', 'modbus rtu on uart1 parity maybe\n',
         E(1, 28, "parity must be none, even or odd, not 'maybe'")),
    case('chart-no-initial', dedent("""\
        chart C {
            step A { }
        }
        """),
         E(1, 7, "chart 'C' has no initial step", hint='mark the step it starts in: initial step Name { ... }')),
    case('chart-two-initials', dedent("""\
        chart C {
            initial step A { }
            initial step B { }
            transition A -> B when true
        }
        """),
         E(3, 5, "chart 'C' has more than one initial step", note=(2, 5, 'the first initial step'))),
    case('chart-unreachable', dedent("""\
        chart C {
            initial step A { }
            step B { }
        }
        """),
         E(3, 10, "step 'B' is unreachable from the initial step 'A'")),
    case('chart-bad-convergence', dedent("""\
        chart C {
            initial step A { }
            step B { }
            step X { }
            transition A -> B when true
            transition (A, B) -> X when true
        }
        """),
         E(4, 10, "step 'X' is unreachable from the initial step 'A'"),
         E(6, 5, 'a convergence must join one step of every branch of a single divergence',
           hint="join exactly the branches that one 'A -> (B, C)' transition started")),
    case('chart-step-from-two-branches', dedent("""\
        chart C {
            initial step I { }
            step L { }
            step R { }
            step J { }
            transition I -> (L, R) when true
            transition L -> J when true
            transition R -> J when true
        }
        """),
         E(8, 5, "step 'J' is entered from two different parallel branches",
           hint='a step belongs to one branch; join branches with a convergence (A, B) -> C',
           note=(7, 5, "'J' is entered here too"))),
    case('chart-duplicate-step', dedent("""\
        chart C {
            initial step A { }
            step A { }
        }
        """),
         E(3, 10, "step 'A' is declared twice in chart 'C'", note=(2, 18, 'first declared here'))),
    case('chart-step-member', dedent("""\
        chart C {
            initial step A { }
            transition A -> A when A.done
        }
        """),
         E(3, 28, "a step offers 'A.time' and 'A.active'")),
    case('task-no-period', 'task t { }\n',
         E(1, 6, "task 't' has no period", hint='write: task name period 10 ms { ... }')),
    case('task-offset-not-below-period', 'task t period 10 ms offset 10 ms { }\n',
         E(1, 21, 'the offset must be below the period (10 ms)')),
    case('task-deadline-above-period', 'task t period 10 ms deadline 20 ms { }\n',
         E(1, 21, 'the deadline must be positive and at most the period (10 ms)')),
    case('task-wcet-above-deadline', 'task t period 10 ms deadline 5 ms wcet 6 ms { }\n',
         E(1, 35, 'the wcet must be positive and at most the deadline (5 ms)')),
    case('task-period-needs-unit', 'task t period 10 { }\n',
         E(1, 15, "the period of task 't' is a 'time': write a duration such as '10 ms'")),
    case('task-runs-unknown', 'task t period 10 ms { run Nothing }\n',
         E(1, 27, "unknown dataflow or chart 'Nothing'")),
    case('task-attr-twice', 'task t period 10 ms period 20 ms { }\n',
         E(1, 21, "'period' is given twice for task 't'")),
    case('task-dataflow-two-tasks', dedent("""\
        import std
        var v: int16
        dataflow D {
            c = Const<int16>(value = 1)
            c.y -> v
        }
        task t1 period 1 ms { run D }
        task t2 period 2 ms { run D }
        """),
         E(8, 23, "dataflow 'D' is run by task 't1' and by task 't2'",
           hint='a dataflow or chart runs in one task; split it, or use a channel between tasks',
           note=(7, 23, "run by task 't1' here"))),
    case('task-dataflow-two-tasks-through-chart', dedent("""\
        import std
        var v: int16
        dataflow D {
            c = Const<int16>(value = 1)
            c.y -> v
        }
        chart C {
            initial step A { run D }
        }
        task t1 period 1 ms { run D }
        task t2 period 2 ms { run C }
        """),
         E(8, 22, "dataflow 'D' is run by task 't1' and by task 't2'",
           hint='a dataflow or chart runs in one task; split it, or use a channel between tasks',
           note=(10, 23, "run by task 't1' here"))),
    case('actor-no-step-no-impl', dedent("""\
        actor type A() {
            out y: int8
        }
        """),
         E(1, 12, "actor type 'A' has no 'step' block and no 'impl' file",
           hint='add step {{ ... }} with the C code of one firing')),
    case('actor-impl-missing', dedent("""\
        actor type A() {
            out y: int8
            impl "actors/a.c"
        }
        """),
         E(3, 5, "implementation file 'actors/a.c' not found (looked at {dir}/actors/a.c)")),
    case('actor-inline-and-impl', dedent("""\
        actor type A() {
            out y: int8
            step {{ y = 1; }}
            impl "a.c"
        }
        """),
         E(4, 5, "an actor type has either inline C blocks or an 'impl' file, not both"), files={'a.c': ''}),
    case('actor-duplicate-port', dedent("""\
        actor type A() {
            in x: int8
            out x: int8
            step {{ x = 1; }}
        }
        """),
         E(3, 9, "'x' is declared twice in actor type 'A'", note=(2, 8, 'first declared here'))),
    case('actor-no-output', dedent("""\
        actor type A() {
            in x: int8
            step {{ }}
        }
        """),
         E(1, 12, "actor type 'A' has no output port")),
    case('actor-two-step-blocks', dedent("""\
        actor type A() {
            out y: int8
            step {{ y = 1; }}
            step {{ y = 2; }}
        }
        """),
         E(4, 5, "actor type 'A' has two 'step' blocks", note=(3, 5, 'the first is here'))),
    case('actor-unknown-bound', dedent("""\
        actor type A<T: numbr>() {
            out y: T
            step {{ y = 0; }}
        }
        """),
         E(1, 14, "unknown type bound 'numbr'", hint="did you mean 'number'?")),
    case('instance-unknown-parameter', dedent("""\
        import std
        var v: int16
        dataflow D {
            c = Gain<int16>(kk = 2)
            v -> c.x
            c.y -> v
        }
        """),
         E(4, 21, "actor type 'Gain' has no parameter 'kk'", hint="did you mean 'k'?")),
    case('instance-missing-parameter', dedent("""\
        import std
        var v: int16
        dataflow D {
            c = Const<int16>()
            c.y -> v
        }
        """),
         E(4, 9, "'c' needs parameter 'value' of actor type 'Const'", hint='write Const(value = ...)')),
    case('instance-sizing-parameter-is-param', dedent("""\
        import std
        param n: uint8 = 8
        var v: int16
        dataflow D {
            a = MovingAverage<int16>(n = n)
            v -> a.x
            a.y -> v
        }
        """),
         E(5, 34, "parameter 'n' of 'a' must be a compile-time constant",
           hint='use literals and consts here, not params, vars or device data')),
    case('instance-choice', dedent("""\
        import std
        var v: int16
        var b: bool
        dataflow D {
            c = Compare<int16>(op = "=>", threshold = 1)
            v -> c.x
            c.y -> b
        }
        """),
         E(5, 29, 'parameter \'op\' of \'c\' must be one of "<", "<=", ">", ">=", "==", "!="')),
    case('instance-var-as-argument', dedent("""\
        import std
        var k: int16
        var v: int16
        dataflow D {
            c = Const<int16>(value = k)
            c.y -> v
        }
        """),
         E(5, 30, "'k' is a var; only consts and params can be given here")),
    case('instance-declared-twice', dedent("""\
        import std
        var v: int16
        dataflow D {
            c = Const<int16>(value = 1)
            c = Const<int16>(value = 2)
            c.y -> v
        }
        """),
         E(5, 5, "actor instance 'c' is declared twice in dataflow 'D'")),
    case('edge-input-not-connected', dedent("""\
        import std
        var v: int16
        dataflow D {
            g = Gain<int16>()
            g.y -> v
        }
        """),
         E(4, 5, "input 'g.x' is not connected", hint='add an edge such as: something -> g.x')),
    case('edge-input-two-edges', dedent("""\
        import std
        var v: int16
        var w: int16
        dataflow D {
            g = Gain<int16>()
            v -> g.x
            w -> g.x
            g.y -> v
        }
        """),
         E(7, 10, "input 'g.x' already has an edge",
           hint='an input port takes exactly one edge; merge the sources with an actor',
           note=(6, 5, 'the other edge'))),
    case('edge-from-input-port', dedent("""\
        import std
        var v: int16
        dataflow D {
            g = Gain<int16>()
            v -> g.x
            g.x -> v
        }
        """),
         E(6, 5, "'g.x' is an input port; an edge starts at an output")),
    case('edge-delay-on-external', dedent("""\
        import std
        var v: int16
        var w: int16
        dataflow D {
            v -> w delay 1
        }
        """),
         E(5, 12, 'initial tokens belong on edges between actors')),
    case('channel-unconnected', 'channel c: int16\n',
         E(1, 9, "channel 'c' has no producer", hint='write to it from a dataflow: x.y -> c'),
         E(1, 9, "channel 'c' has no consumer", hint='read it in a dataflow: c -> x.in')),
    case('channel-no-consumer', dedent("""\
        import std
        channel c: int16
        dataflow D {
            k = Const<int16>(value = 1)
            k.y -> c
        }
        """),
         E(2, 9, "channel 'c' has no consumer", hint='read it in a dataflow: c -> x.in')),
    # the only producing (consuming) edge's type mismatch is the only error:
    # the channel is not also reported as without a producer (consumer)
    case('channel-producer-type-mismatch', dedent("""\
        import std
        channel c: int16
        dataflow P {
            k = Const<int32>(value = 1)
            k.y -> c
        }
        dataflow C {
            g = Gain<int16>()
            c -> g.x
        }
        task tp period 1 ms { run P }
        task tc period 1 ms { run C }
        """),
         E(5, 5, "type mismatch: 'k.y' is 'int32' but 'c' is 'int16'", hint='convert with Cast<int32, int16>()')),
    case('channel-consumer-type-mismatch', dedent("""\
        import std
        channel c: int32
        dataflow P {
            k = Const<int32>(value = 1)
            k.y -> c
        }
        dataflow C {
            g = Gain<int16>()
            c -> g.x
        }
        task tp period 1 ms { run P }
        task tc period 1 ms { run C }
        """),
         E(9, 5, "type mismatch: 'c' is 'int32' but 'g.x' is 'int16'", hint='convert with Cast<int32, int16>()')),
    case('device-driver-and-parts', dedent("""\
        import std
        device type X() {
            part a: AnalogIn(channel = 1)
            driver "x"
        }
        """),
         E(4, 5, 'a device type with a driver is primitive and cannot have parts',
           hint='move the driver into a device type of its own and make it a part')),
    case('device-ports-without-driver', dedent("""\
        device type X() {
            out a: int8
        }
        """),
         E(1, 13, "device type 'X' has data ports but no driver",
           hint='add driver "name", or re-export a part\'s data with out x = part.y')),
    case('device-bad-export', dedent("""\
        import std
        device type X() {
            part a: AnalogIn(channel = 1)
            out v = a.valeu
        }
        device x: X()
        """),
         E(4, 13, "'a.valeu' is not a data port of a part of device type 'X'")),
    case('device-export-direction', dedent("""\
        import std
        device type X() {
            part a: AnalogIn(channel = 1)
            in v = a.value
        }
        device x: X()
        """),
         E(4, 5, "'v' is declared 'in' but 'a.value' is 'out'")),
    case('device-contains-itself', dedent("""\
        device type X() {
            part x: X()
        }
        device d: X()
        """),
         E(2, 13, "device type 'X' contains itself")),
    case('device-mutual-containment', dedent("""\
        device type X() {
            part y: Y()
        }
        device type Y() {
            part x: X()
        }
        device d: X()
        """),
         E(5, 13, "device type 'X' contains itself (X -> Y -> X)")),
    case('device-unknown-parameter', dedent("""\
        import std
        device a: AnalogIn(chanel = 1)
        """),
         E(2, 20, "device type 'AnalogIn' has no parameter 'chanel'", hint="did you mean 'channel'?")),
    case('device-missing-parameter', dedent("""\
        import std
        device a: AnalogIn()
        """),
         E(2, 1, "device type 'AnalogIn' needs parameter 'channel'")),
    case('device-unknown-datum', dedent("""\
        import std
        device sensor: Pt100(channel = 0)
        var v: uint16
        dataflow D {
            sensor.rwa -> v
        }
        """),
         E(5, 5, "device 'sensor' has no part or datum 'rwa'", hint="did you mean 'raw'?")),
    case('actor-unknown-bound-used', dedent("""\
        actor type A<T: numbr>() {
            in  x: T
            out y: T
            step {{ y = x; }}
        }
        dataflow D {
            a = A<int16>()
        }
        """),
         E(1, 14, "unknown type bound 'numbr'", hint="did you mean 'number'?")),
    case('safe-value-out-of-range', dedent("""\
        import std
        device m: Motor(pwm = "PB1", dir = "PB2") safe speed = 40000
        """),
         E(2, 56, "the safe value of 'm.speed': 40000 does not fit 'int16' (-32768..32767)")),
    case('safe-value-of-wrong-type', dedent("""\
        import std
        device lamp: DigitalOut(pin = "PB5") safe level = 1
        """),
         E(2, 51, "the safe value of 'lamp.level' expects 'bool' but the value is an integer constant")),
    case('safe-value-on-a-sensor-output', dedent("""\
        import std
        device sensor: Pt100(channel = 0) safe raw = 0
        """),
         E(2, 40, "'sensor.raw' is an out datum (read from the device): only in data have safe values")),
    case('safe-value-of-an-unknown-datum', dedent("""\
        import std
        device lamp: DigitalOut(pin = "PB5") safe levle = true
        """),
         E(2, 43, "device 'lamp' has no datum 'levle'", hint="did you mean 'level'?")),
    case('safe-value-given-twice', dedent("""\
        import std
        device lamp: DigitalOut(pin = "PB5") safe level = true, level = false
        """),
         E(2, 57, "the safe value of 'lamp.level' is given twice", note=(2, 43, "first given here"))),
    case('safe-value-not-a-constant', dedent("""\
        import std
        param p: int16 = 3
        device m: Motor(pwm = "PB1", dir = "PB2") safe speed = p
        """),
         E(3, 56, "'p' is a param, known only at run time; a compile-time constant is needed here",
           hint="use literals and consts here")),
    case('remote-settings', dedent("""\
        remote watchdog 0 ms overruns 256
        remote overruns 2 overruns 3
        """),
         E(1, 17, "the watchdog time is a positive whole number of microseconds"),
         E(1, 31, "'overruns' counts overruns in a row: 1 to 255, not 256"),
         E(2, 1, "a model has at most one 'remote' declaration", note=(1, 1, "the other one"))),
    case('device-driver-name', dedent("""\
        device type X() {
            out a: int8
            driver "Analog-In"
        }
        """),
         E(3, 5, "driver name 'Analog-In' must be a C identifier in lower case")),
    case('data-duplicate-register', dedent("""\
        var a: int16 service ro @ 5
        var b: int16 service ro @ 5
        var c: int16 service rw @ 5
        var d: bool service rw @ 5
        """),
         E(2, 14, "input register 5 is given to 'a' and to 'b'",
           hint='give each item its own address, or leave the address out to have one assigned',
           note=(1, 14, "'a' has it here"))),
    case('data-overlapping-registers', dedent("""\
        param a: int32 service rw @ 10
        var b: int16 service rw @ 11
        var c: bool service rw @ 10
        """),
         E(2, 14, "holding register 11 of 'b' overlaps 'a' (10..11)",
           hint='give each item its own address, or leave the address out to have one assigned',
           note=(1, 16, "'a' has it here"))),
    case('data-time-too-long', 'param t: time = 5000000000 s\n',
         E(1, 17, "the initial value of param 't': a 'time' is from 0 to 4294967295 ms")),
    case('data-time-not-whole-ms', 'var t: time = 1500 us\n',
         E(1, 15, "a run-time 'time' value counts whole milliseconds")),
    case('syntax-expression-too-deep', "const C: int16 = " + "-" * 101 + "1\n",
         E(1, 18, 'expression nested more than 100 operators deep', hint='split it up with consts')),
    case('syntax-leading-zeros-are-decimal', 'const C: int8 = 0128\n',
         E(1, 17, "const 'C': 128 does not fit 'int8' (-128..127)")),
    case('device-choice', dedent("""\
        device type X(mode: uint8 in (1, 2)) {
            out v: int8
            driver "x"
        }
        device x: X(mode = 3)
        """),
         E(5, 20, "device parameter 'mode' must be one of 1, 2")),
    case('device-bad-default-no-follow-on', dedent("""\
        import std
        device type X(c: uint8 = 300) {
            part a: AnalogIn(channel = c)
            out v = a.value
        }
        device x: X()
        """),
         E(2, 26, "the default of 'c': 300 does not fit 'uint8' (0..255)")),
    case('actor-choices-of-wrong-type', dedent("""\
        actor type A(op: string in (1, 2)) {
            out y: int8
            step {{ y = 1; }}
        }
        var v: int8
        dataflow D {
            a = A(op = "x")
            a.y -> v
        }
        """),
         E(1, 29, "a choice expects 'string' but the value is an integer constant"),
         E(1, 32, "a choice expects 'string' but the value is an integer constant")),
    case('type-guard-time-needs-unit', dedent("""\
        chart C {
            initial step A { }
            transition A -> A when A.time > 5
        }
        """),
         E(3, 37, "'>' mixes a 'time' with a plain number: write a duration such as '5 ms'")),
    case('task-period-too-long', 'task t period 50000000 s { }\n',
         E(1, 15, "the period of task 't': a 'time' is from 0 to 4294967295 ms")),
    case('name-misspelt-step-in-guard', dedent("""\
        chart C {
            initial step Idle { }
            transition Idle -> Idle when Idel.time > 1 s
        }
        """),
         E(3, 34, "unknown name 'Idel'", hint="did you mean 'Idle'?")),
    case('keyword-as-name-still-checked', dedent("""\
        import std
        var v: int16
        dataflow D {
            k = Const<int16>(value = 1)
            k.y -> v
            offset = Gain<int16>()
            k.y -> offset.x
            offset.z -> v
        }
        """),
         E(8, 12, "actor 'offset' (Gain) has no port 'z'", hint="its ports: x, y")),
]


def _same_file(shown: str, path: Path) -> bool:
    return Path(shown).resolve() == path.resolve()


@pytest.mark.parametrize("text, expected, files", CASES)
def test_bad_model(check_model, text, expected, files):
    result, path = check_model(text, files)
    assert result.model is None

    def fill(s):
        return None if s is None else s.replace("{dir}", str(path.parent))

    diags = result.diagnostics.sorted()
    assert [(d.span.line, d.span.column, d.message) for d in diags] == \
        [(e.line, e.col, fill(e.message)) for e in expected]
    for d, e in zip(diags, expected):
        assert _same_file(d.span.file, path)
        assert d.hint == fill(e.hint), d.message
        if e.note is None:
            assert not d.notes, d.message
        else:
            line, col, message, *file = e.note
            n = d.notes[0]
            assert (n.span.line, n.span.column, n.message) == (line, col, message)
            assert (n.span.file == file[0]) if file else _same_file(n.span.file, path)
    first = diags[0]
    assert f"{first.span}: error: {first.message}" in result.report()


# ------------------------------------------------------------ several files


def test_import_cycle_across_two_files(tmp_path):
    (tmp_path / "a.elab").write_text('import "b.elab"\nvar x: int8\n')
    (tmp_path / "b.elab").write_text('var y: int8\nimport "a.elab"\n')
    result = check_file(tmp_path / "a.elab")
    assert result.model is None
    [d] = result.diagnostics.sorted()
    assert _same_file(d.span.file, tmp_path / "b.elab")
    assert (d.span.line, d.span.column, d.message, d.hint) == \
        (2, 1, "import cycle: a.elab -> b.elab -> a.elab", "remove one of these imports")


def test_import_from_a_subfolder_reports_in_that_file(tmp_path):
    (tmp_path / "lib").mkdir()
    (tmp_path / "lib" / "more.elab").write_text('import "deeper.elab"\n')
    (tmp_path / "lib" / "deeper.elab").write_text("var q: int8 =\n")
    (tmp_path / "m.elab").write_text('import "lib/more.elab"\nvar x: int8\n')
    result = check_file(tmp_path / "m.elab")
    [d] = result.diagnostics.sorted()
    assert _same_file(d.span.file, tmp_path / "lib" / "deeper.elab")
    assert (d.span.line, d.span.column, d.message) == (1, 14, "unexpected end of the file, expected an expression")


def test_a_name_clash_with_an_imported_file_notes_the_first(tmp_path):
    (tmp_path / "lib.elab").write_text("var\n  speed: int16\n")
    (tmp_path / "m.elab").write_text('import "lib.elab"\nparam speed: int16\n')
    result = check_file(tmp_path / "m.elab")
    [d] = result.diagnostics.sorted()
    assert (d.span.line, d.span.column, d.message) == (2, 7, "'speed' is already declared as a var")
    [n] = d.notes
    assert _same_file(n.span.file, tmp_path / "lib.elab")
    assert (n.span.line, n.span.column, n.message) == (2, 3, "'speed' is first declared here")


def test_every_error_is_reported_in_one_run(check_model):
    result, _ = check_model(dedent("""\
        import std
        var a: int8 = 300
        param p: int16 = 5 range 10..20
        var v: int16 persist
        task t { }
        """))
    assert [(d.span.line, d.span.column) for d in result.diagnostics.sorted()] == [(2, 15), (3, 18), (4, 14), (5, 6)]


def test_byte_order_mark_and_crlf_are_no_errors(tmp_path):
    (tmp_path / "m.elab").write_bytes(b"\xef\xbb\xbfvar x: int8\r\nvar y: int8 = z\r\n")
    result = check_file(tmp_path / "m.elab")
    [d] = result.diagnostics.sorted()
    assert (d.span.line, d.span.column, d.message) == (2, 15, "unknown name 'z'")
    assert "    2 | var y: int8 = z\n" in result.report()
