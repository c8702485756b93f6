"""Distribution rules: nodes, links, where tasks and devices run, channels
between nodes and exports (docs/language.md §11, docs/distribution.md).

A model without ``node`` declarations is checked exactly as before: none of
these rules apply to it. In a model with nodes every task and device is
``on`` a node, a var or device datum is used on one node only, and a
channel between tasks of two nodes goes ``over`` a link that reaches both.
"""

from __future__ import annotations

from ...core import types as T
from ...core.expr import refs
from ...core.source import did_you_mean, note
from .. import ast
from ..model import DataInfo, DeviceDatum, ExportInfo, LinkInfo, LinkMemberInfo, NodeInfo

# Which settings each engine takes, their kinds, and their defaults.
_LINK_KEYS = {
    "modbus-rtu": {"baud": "int", "parity": "name", "round": "time", "turnaround": "time", "jitter": "time"},
    "dds": {"domain": "int", "latency": "time", "jitter": "time"},
}
_LINK_DEFAULTS = {
    "modbus-rtu": {"baud": 19200, "parity": "even", "turnaround": 1000, "jitter": 0},
    "dds": {"domain": 0, "latency": 1000, "jitter": 0},
}
_ROLES = {"modbus-rtu": ("master", "slave"), "dds": ("peer",)}


class NodeRules:
    # ================================================================ nodes and links

    def check_node(self, decl: ast.NodeDecl) -> None:
        if decl.cores is not None and not 1 <= decl.cores <= 64:
            self.error(decl.cores_span, f"node '{decl.name}' has {decl.cores} cores: a node runs on 1 to 64",
                       "write: cores 2 (docs/multicore.md)")
        self.nodes[decl.name] = NodeInfo(decl, decl.board, decl.mcu)

    def check_link(self, decl: ast.LinkDecl) -> None:
        keys = _LINK_KEYS[decl.engine]
        settings: dict[str, object] = dict(_LINK_DEFAULTS[decl.engine])
        given: set[str] = set()
        for a in decl.attrs:
            value = self._link_setting(a, keys, given, f"link '{decl.name}'")
            if value is not None:
                settings[a.key] = value
        if decl.engine == "modbus-rtu" and "round" not in given:
            self.error(decl.name_span, f"Modbus link '{decl.name}' has no round period",
                       f"write: link {decl.name} modbus rtu baud 115200 round 20 ms {{ ... }}")
        members: list[LinkMemberInfo] = []
        units: dict[int, ast.LinkMember] = {}
        for m in decl.members:
            member = self._link_member(decl, m, units)
            if member is None:
                continue
            other = next((o for o in members if o.node is member.node), None)
            if other is not None:
                self.error(m.node_span, f"node '{m.node}' is on link '{decl.name}' twice",
                           notes=[note(other.decl.span, "first here")])
                continue
            members.append(member)
        if decl.engine == "modbus-rtu":
            masters = [m for m in members if m.role == "master"]
            if len(masters) != 1:
                self.error(decl.name_span, f"Modbus link '{decl.name}' needs exactly one master, "
                                           f"not {len(masters)}", "write: master NODE")
            if not any(m.role == "slave" for m in members):
                self.error(decl.name_span, f"Modbus link '{decl.name}' has no slave",
                           "write: slave NODE on uart0 unit 2")
        self.links[decl.name] = LinkInfo(decl, decl.engine, settings, members)

    def _link_setting(self, a: ast.LinkAttr, keys: dict[str, str], given: set[str], where: str):
        """A link or member setting's value in run-time units, or None after an error."""
        if a.key not in keys:
            self.error(a.span, f"'{a.key}' is not a setting of {where}",
                       f"its settings: {', '.join(keys)}")
            return None
        if a.key in given:
            self.error(a.span, f"'{a.key}' is given twice for {where}")
            return None
        given.add(a.key)
        kind = keys[a.key]
        if kind == "name":
            if not (isinstance(a.value, ast.Path) and len(a.value.parts) == 1
                    and a.value.parts[0] in ("none", "even", "odd")):
                self.error(a.value.span, "parity must be none, even or odd")
                return None
            return a.value.parts[0]
        v = self.const_typer().expect_const(a.value, T.TIME if kind == "time" else None, f"the {a.key}")
        if v.type is None:
            return None
        value = v.const
        if kind == "time":
            if value < 0 or value.denominator != 1 or (a.key == "round" and value == 0):
                self.error(a.value.span, f"the {a.key} is a {'positive' if a.key == 'round' else 'non-negative'} "
                                         "whole number of microseconds")
                return None
            return int(value)
        if not isinstance(value, int) or isinstance(value, bool):
            self.error(a.value.span, f"'{a.key}' takes an integer")
            return None
        limits = {"baud": (300, 4_000_000), "unit": (1, 247), "domain": (0, 232)}[a.key]
        if not limits[0] <= value <= limits[1]:
            self.error(a.value.span, f"the {a.key} {value} is outside {limits[0]}..{limits[1]}")
            return None
        return value

    def _link_member(self, decl: ast.LinkDecl, m: ast.LinkMember, units: dict) -> LinkMemberInfo | None:
        node = self.nodes.get(m.node)
        if node is None:
            self.lookup(m.node, m.node_span, (ast.NodeDecl,), "node")
            return None
        roles = _ROLES[decl.engine]
        engine = "a Modbus RTU link" if decl.engine == "modbus-rtu" else "a DDS link"
        if m.role not in roles:
            self.error(m.span, f"{engine} has no '{m.role}'", f"its members are: {', '.join(roles)} NODE")
            return None
        given: set[str] = set()
        unit = None
        for a in m.attrs:
            keys = {"unit": "int"} if m.role == "slave" else {}
            value = self._link_setting(a, keys, given, f"the {m.role} '{m.node}'")
            if value is not None:
                unit = value
        uart = None
        if m.role == "slave":
            if unit is None and not any(a.key == "unit" for a in m.attrs):
                self.error(m.span, f"slave '{m.node}' of link '{decl.name}' has no unit id", "add: unit 2")
            if unit is not None and unit in units:
                self.error(m.span, f"unit id {unit} is used twice on link '{decl.name}'",
                           notes=[note(units[unit].span, "first here")])
            elif unit is not None:
                units[unit] = m
            if m.resource is None:
                self.error(m.span, f"slave '{m.node}' of link '{decl.name}' needs the UART it is on: 'on uart0'")
        if m.resource is not None:
            if m.role == "peer":
                self.error(m.resource.span, "a DDS peer runs on its node's network, not 'on' a resource")
            else:
                uart = self.eval_claim(m.resource, self.const_typer(), f"link {decl.name}")
                if uart is not None and uart.kind != "uart":
                    self.error(m.resource.span, f"a Modbus link runs on a UART, not on '{uart}'")
                    uart = None
                if uart is not None:
                    uart.node = node.name
                    self.claims.append(uart)
        return LinkMemberInfo(node, m.role, uart, unit, m)

    # ================================================================ placement

    def check_placement(self) -> None:
        """Every task and device on a node (when there are nodes), every
        var and device datum used on one node, channels between nodes over
        a link that reaches both, exports on a peer of their link."""
        placed = [("task", d.name, d.node, d) for d in self._decls(ast.Task)] + \
                 [("device", d.name, d.node, d) for d in self._decls(ast.DeviceInstance)]
        for what, name, where, decl in placed:
            if where is None:
                if self.nodes:
                    self.error(decl.name_span, f"{what} '{name}' is on no node: a model with nodes places every "
                                               "task and device", f"write: ... on {next(iter(self.nodes))}")
                continue
            if where.name not in self.nodes:
                self.lookup(where.name, where.name_span, (ast.NodeDecl,), "node")
                continue
            (self.task_nodes if what == "task" else self._top_device_nodes)[name] = where.name
        for device in self.devices:
            node = self._top_device_nodes.get(device.path.split(".")[0])
            if node is not None:
                self.device_nodes[device.path] = node
                for c in device.claims:
                    c.node = node
        if not self.nodes:
            for decl in self._decls(ast.Channel):
                if decl.over is not None:
                    self.error(decl.over.span, f"channel '{decl.name}' goes over a link, but the model has no nodes")
            return
        for module in self.modules:
            for iface in module.interfaces:
                self.error(iface.span, "a model with nodes has no model-wide interface: each node's debug and "
                                       "service interfaces are not placed yet (docs/distribution.md)")
        self._check_single_node_data()
        for ch in self.channels.values():
            self._check_channel_link(ch)
        for module in self.modules:
            for export in module.exports:
                self._check_export(export)

    def node_of_task(self, task) -> str | None:
        return self.task_nodes.get(task.name) if task is not None else None

    def _check_single_node_data(self) -> None:
        """A var or device datum lives on one node: every dataflow edge and
        chart expression that uses it runs there."""
        uses: dict[int, list] = {}  # id(target) -> [(target, node, span), ...]

        def use(target, task, span) -> None:
            node = self.node_of_task(task)
            if node is not None and isinstance(target, (DataInfo, DeviceDatum)) \
                    and not (isinstance(target, DataInfo) and target.kind == "param"):
                uses.setdefault(id(target), []).append((target, node, span))

        for df in self.dataflows.values():
            for e in df.edges:
                for end in (e.src, e.dst):
                    if end.kind in ("var", "device"):
                        use(end.target, df.task, end.path.span)
        for chart in self.charts.values():
            for tr in chart.transitions:
                for r in refs(tr.guard) if tr.guard is not None else ():
                    use(r.target, chart.task, tr.decl.guard.span)
            for step in chart.steps.values():
                for action in (*step.entry_actions, *step.exit_actions):
                    use(action.target, chart.task, action.decl.span)
                    for r in refs(action.value):
                        use(r.target, chart.task, action.decl.span)
        for found in uses.values():
            target = found[0][0]
            home = self.device_nodes.get(target.device.path) if isinstance(target, DeviceDatum) else found[0][1]
            label = f"device datum '{target.name}'" if isinstance(target, DeviceDatum) else f"var '{target.name}'"
            for _t, node, span in found:
                if node != home:
                    self.error(span, f"{label} is on node '{home}' but used here on node '{node}'",
                               "data crosses nodes through a channel over a link")
                    break

    def _check_channel_link(self, ch) -> None:
        if not ch.producers or not ch.consumers:
            return  # reported by the checker
        p_task, c_task = self._edge_task(ch.producers[0]), self._edge_task(ch.consumers[0])
        p_node, c_node = self.node_of_task(p_task), self.node_of_task(c_task)
        if p_node is None or c_node is None:
            return
        over = ch.decl.over
        ends = (f"from task '{p_task.name}' on node '{p_node}' to task '{c_task.name}' on node '{c_node}'")
        both = [note(ch.producers[0].decl.span, f"produced on node '{p_node}' here"),
                note(ch.consumers[0].decl.span, f"consumed on node '{c_node}' here")]
        if p_node == c_node:
            if over is not None:
                self.error(over.span, f"channel '{ch.name}' goes {ends}: both ends are on one node, it needs "
                                      "no link", f"remove 'over {over.name}'")
            return
        if over is None:
            links = [lk.name for lk in self.links.values() if lk.member(p_node) and lk.member(c_node)]
            self.error(ch.decl.name_span, f"channel '{ch.name}' goes {ends} but names no link",
                       f"add: over {links[0]}" if links else f"declare a link that reaches '{p_node}' and "
                                                                 f"'{c_node}', and add: over LINK", both)
            return
        link = self.links.get(over.name)
        if link is None:
            self.lookup(over.name, over.name_span, (ast.LinkDecl,), "link")
            return
        for node in (p_node, c_node):
            if link.member(node) is None:
                self.error(over.name_span, f"channel '{ch.name}' goes {ends} over link '{link.name}', which does "
                                           f"not reach node '{node}'",
                           f"add node '{node}' to link '{link.name}', or choose another link",
                           [note(link.decl.name_span, f"link '{link.name}' is declared here"), *both])
                return
        ch.link = link

    def _check_export(self, export: ast.Export) -> None:
        target = self.data.get(export.name) or self.channels.get(export.name)
        if target is None or (isinstance(target, DataInfo) and target.kind != "var"):
            candidates = [n for n, d in self.data.items() if d.kind == "var"] + list(self.channels)
            self.error(export.name_span, f"'{export.name}' is not a var or channel to export",
                       did_you_mean(export.name, candidates))
            return
        link = self.links.get(export.link.name)
        if link is None or link.engine != "dds":
            if link is None:
                self.lookup(export.link.name, export.link.name_span, (ast.LinkDecl,), "link")
            else:
                self.error(export.link.name_span, f"link '{link.name}' is a Modbus bus: exports go over a DDS link")
            return
        if isinstance(target, DataInfo):
            writer = next((w.owner.task for w in target.writers if w.owner.task is not None), None)
        else:
            writer = self._edge_task(target.consumers[0]) if target.consumers else None
        node = self.node_of_task(writer)
        if node is None:
            self.error(export.name_span, f"'{export.name}' is not computed by any task: nothing to export")
            return
        if link.member(node) is None:
            self.error(export.link.name_span, f"'{export.name}' is on node '{node}', which is no peer of DDS link "
                                              f"'{link.name}'", f"add to the link: peer {node}",
                       [note(link.decl.name_span, f"link '{link.name}' is declared here")])
            return
        self.exports.append(ExportInfo(export, target, link, self.nodes[node]))

    def _edge_task(self, edge):
        """The task that runs the dataflow of an edge, or None."""
        return next((df.task for df in self.dataflows.values() if edge in df.edges), None)
