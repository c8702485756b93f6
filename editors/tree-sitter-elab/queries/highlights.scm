; Written by tools/tree_sitter_grammar.py from generator/frontend/elab.lark: edit that, not this.

(comment) @comment
(string) @string
[(int) (real)] @number
(c_code) @embedded
(persist_attr) @keyword

["actor" "addr" "baud" "board" "channel" "chart" "claims" "conditions" "const" "cores" "cost" "cs" "dataflow" "dds" "deadline" "debug" "delay" "device" "domain" "driver" "entry" "exit" "export" "flat" "force" "impl" "import" "in" "initial" "jitter" "latency" "link" "master" "mcu" "min-buffer" "modbus" "model" "node" "offset" "on" "out" "over" "overruns" "param" "parity" "part" "peer" "period" "persist" "port" "range" "rate" "remote" "ro" "round" "rtu" "run" "rw" "safe" "sas" "scale" "schedule" "service" "sim" "slave" "start" "state" "step" "stop" "task" "tcp" "transition" "turnaround" "type" "unit" "var" "watchdog" "wcet" "when"] @keyword
["and" "or" "not"] @keyword.operator
["true" "false"] @boolean
(duration_lit ["us" "ms" "s"] @type.builtin)

["!=" "%" "*" "+" "-" "->" ".." "/" "<" "<=" "=" "==" ">" ">="] @operator
["(" ")" "[" "]" "{" "}"] @punctuation.bracket
["," "." ":" "@"] @punctuation.delimiter

; The name a declaration introduces (the first name of the node).
(model_decl . (name) @module)
(import_decl . (name) @module)
(const_decl . (name) @constant)
(param_decl . (name) @variable)
(var_decl . (name) @variable)
(channel_decl . (name) @variable)
(device_type . (name) @type)
(actor_type . (name) @type)
(type_ref . (name) @type)
(type_param . (name) @type)
(dataflow . (name) @function)
(chart . (name) @function)
(task . (name) @function)
(run_action . (name) @function)
(step . (name) @label)
(step_set . (name) @label)
(state_var . (name) @variable)
(actor_port . (name) @property)
(data_port . (name) @property)
(data_export . (name) @property)
(formal_param . (name) @variable.parameter)
(actual . (name) @variable.parameter)
(node_decl . (name) @module)
(link_decl . (name) @module)
(instance (name) @variable (name) @type)
(device_decl (name) @variable (name) @type)
(path (name) @variable)
