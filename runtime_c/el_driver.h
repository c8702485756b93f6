/* EasyLab runtime: what every board's device drivers share
 * (docs/boards.md, "Writing a device driver").
 *
 * A driver implements the six handlers of a device (open, start, read,
 * write, stop, close) as functions of its constant description. Most
 * drivers have nothing to do in some of them (a sensor writes nothing, a
 * pin needs no start): EL_DRV_NOTHING defines such a handler, so that the
 * dispatcher can call every handler of every device alike.
 */
#ifndef EL_DRIVER_H
#define EL_DRIVER_H

/* A handler `name` of description type `type` that does nothing. */
#define EL_DRV_NOTHING(name, type) \
    static inline void name(const type *d) { (void)d; }

#endif /* EL_DRIVER_H */
