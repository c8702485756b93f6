"""Remote execution (docs/remote.md): the application runs in the
interpreter on this machine, a proxy generated from the device model runs
on the target and forwards its devices' data."""
