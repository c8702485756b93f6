"""The register addresses of a Modbus link's round on every slave
(docs/distribution.md): one source for the timing analysis, the round
table's JSON and the generated master and slaves."""

SYNC_REGISTER = 0xE000  # the broadcast round number (function 6 to unit 0)
READ_BASE = 0xE100  # read block: the status register (round last taken), then the slave's outputs
WRITE_BASE = 0xE200  # write block: the slave's inputs (the round number when it has none)

__all__ = ["READ_BASE", "SYNC_REGISTER", "WRITE_BASE"]
