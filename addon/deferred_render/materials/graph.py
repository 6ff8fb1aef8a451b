"""Where a node input's value comes from, through Blender's indirections.

A shader node tree is not a plain graph: links pass through reroutes, node
groups (``ShaderNodeGroup`` -> its tree's Group Output; ``NodeGroupInput``
-> the group node's own input socket, one level out), muted nodes (their
``internal_links``: each output takes the input Blender routes to it, else
nothing) and muted or invalid links, or links of disabled sockets (as if
absent). ``resolve_input``
follows all of them and answers with the real node output that drives the
input, or with the unlinked socket whose value it takes.

A context is the tuple of group nodes entered, outermost first: the same
node inside a group used twice is two different sources.
"""

MAX_GROUP_DEPTH = 32
MAX_HOPS = 4096


class Output:
    """A real node output: (node, socket) inside group context ``ctx``."""

    __slots__ = ("node", "socket", "ctx")

    def __init__(self, node, socket, ctx):
        self.node, self.socket, self.ctx = node, socket, ctx


class Unlinked:
    """No link reaches the input: it takes ``socket``'s own value (the input
    itself, a group node's input, or a muted node's passed-through input).
    ``socket`` is None where Blender gives nothing (a muted node without an
    internal link, an unconnected reroute): the input's default applies."""

    __slots__ = ("socket",)

    def __init__(self, socket):
        self.socket = socket


class GraphError(Exception):
    """The tree cannot be followed (too deep, a loop through groups)."""


def _active_link(socket):
    if not socket.is_linked:
        return None
    for link in socket.links:
        # Links from or to a disabled socket (e.g. Voronoi's W output in 3D)
        # are ignored by Blender and Cycles: the input keeps its own value.
        if link.is_valid and not link.is_muted and link.from_socket.enabled and link.to_socket.enabled:
            return link
    return None


def group_output_node(tree):
    """The Group Output Blender evaluates: the active one, else the first."""
    outputs = [n for n in tree.nodes if n.bl_idname == "NodeGroupOutput"]
    for n in outputs:
        if getattr(n, "is_active_output", False):
            return n
    return outputs[0] if outputs else None


def _socket_by_identifier(sockets, identifier):
    for s in sockets:
        if s.identifier == identifier:
            return s
    return None


def resolve_input(socket, ctx=()):
    """Output or Unlinked for an input socket in context ``ctx``."""
    hops = 0
    while True:
        hops += 1
        if hops > MAX_HOPS:
            raise GraphError("links loop through reroutes or groups")
        link = _active_link(socket)
        if link is None:
            return Unlinked(socket)
        node, out = link.from_node, link.from_socket
        result = _resolve_output(node, out, ctx)
        if isinstance(result, tuple):  # continue with another input socket
            socket, ctx = result
            continue
        return result


def _resolve_output(node, out, ctx):
    """Output / Unlinked, or (input socket, ctx) to continue from."""
    kind = node.bl_idname
    if kind == "NodeReroute":
        if not node.inputs[0].is_linked:
            return Unlinked(None)
        return node.inputs[0], ctx
    if node.mute:
        for il in node.internal_links:
            if il.to_socket == out:
                return il.from_socket, ctx
        return Unlinked(None)
    if kind == "ShaderNodeGroup":
        tree = node.node_tree
        if tree is None:
            return Unlinked(None)
        if len(ctx) >= MAX_GROUP_DEPTH:
            raise GraphError(f"node groups nested deeper than {MAX_GROUP_DEPTH}")
        if any(g.node_tree == tree for g in ctx):
            raise GraphError(f"node group '{tree.name}' contains itself")
        output = group_output_node(tree)
        if output is None:
            return Unlinked(None)
        inner = _socket_by_identifier(output.inputs, out.identifier)
        if inner is None:
            return Unlinked(None)
        return inner, ctx + (node,)
    if kind == "NodeGroupInput":
        if not ctx:
            return Unlinked(None)
        group = ctx[-1]
        outer = _socket_by_identifier(group.inputs, out.identifier)
        if outer is None:
            return Unlinked(None)
        return outer, ctx[:-1]
    return Output(node, out, ctx)


def socket_kind(socket):
    """'float', 'color', 'vector' or 'closure' for a Blender socket."""
    t = socket.type
    if t == "RGBA":
        return "color"
    if t == "VECTOR":
        return "vector"
    if t == "SHADER":
        return "closure"
    return "float"  # VALUE, INT, BOOLEAN (and anything else read as a number)
