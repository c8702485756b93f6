/* EasyLab host board: non-volatile storage (el_port_nv_read/write).
 *
 * A store of EL_HOST_NV_SIZE bytes, erased (all 0xFF) at first. With
 * --nvram FILE it lives in FILE, exactly EL_HOST_NV_SIZE bytes long: a
 * missing FILE reads as erased and is created at the first write (written
 * whole to FILE.tmp, synced, then renamed over FILE, so FILE is either
 * missing or complete); later writes go to FILE at once with pwrite and
 * fsync, so a process killed at any moment leaves every byte either old or
 * new. Reads come from a copy in memory, loaded at start. Without --nvram
 * the store lives in memory only, for the length of the run.
 */
#ifndef _POSIX_C_SOURCE
#define _POSIX_C_SOURCE 200809L
#endif

#include "host_internal.h"

#include <errno.h>
#include <fcntl.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>
#include <sys/types.h>
#include <unistd.h>

static uint8_t nv_mem[EL_HOST_NV_SIZE];
static const char *nv_path;
static int nv_fd = -1;

void el_host_nv_close(void)
{
    if (nv_fd >= 0)
        close(nv_fd);
    nv_fd = -1;
    nv_path = NULL;
}

/* Write `size` bytes at `offset` of fd, through short writes and EINTR. */
static bool write_all(int fd, const uint8_t *data, size_t size, off_t offset)
{
    while (size > 0u) {
        ssize_t n = pwrite(fd, data, size, offset);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            return false;
        }
        data += n;
        size -= (size_t)n;
        offset += n;
    }
    return true;
}

static bool read_all(int fd, uint8_t *data, size_t size)
{
    off_t offset = 0;
    while (size > 0u) {
        ssize_t n = pread(fd, data, size, offset);
        if (n < 0) {
            if (errno == EINTR)
                continue;
            return false;
        }
        if (n == 0) {
            errno = EIO;
            return false;
        }
        data += n;
        size -= (size_t)n;
        offset += n;
    }
    return true;
}

/* The directory part of nv_path ("." when none), in a malloc'd string. */
static char *directory_of(const char *path)
{
    const char *slash = strrchr(path, '/');
    size_t n = slash == NULL ? 1u : slash == path ? 1u : (size_t)(slash - path);
    char *dir = malloc(n + 1u);
    if (dir == NULL)
        return NULL;
    if (slash == NULL)
        dir[0] = '.';
    else
        memcpy(dir, path, n);
    dir[n] = '\0';
    return dir;
}

bool el_host_nv_open(const char *path)
{
    struct stat st;
    int fd;

    el_host_nv_close();
    memset(nv_mem, 0xFF, sizeof nv_mem);
    if (path == NULL)
        return true;
    if (path[0] == '\0') {
        el_host_error("--nvram needs a file name");
        return false;
    }
    fd = open(path, O_RDWR);
    if (fd < 0) {
        char *dir;
        int err;
        if (errno != ENOENT) {
            el_host_error("cannot open nvram %s: %s", path, strerror(errno));
            return false;
        }
        /* Created at the first write: check now that it can be. */
        dir = directory_of(path);
        if (dir == NULL) {
            el_host_error("out of memory");
            return false;
        }
        err = access(dir, W_OK | X_OK) == 0 ? 0 : errno;
        free(dir);
        if (err != 0) {
            el_host_error("cannot create nvram %s: %s", path, strerror(err));
            return false;
        }
        nv_path = path;
        return true;
    }
    if (fstat(fd, &st) != 0 || !S_ISREG(st.st_mode)) {
        el_host_error("nvram %s: not a regular file", path);
        close(fd);
        return false;
    }
    if (st.st_size != (off_t)EL_HOST_NV_SIZE) {
        el_host_error("nvram %s: %lld bytes, expected %u (delete it to start erased)", path,
                      (long long)st.st_size, (unsigned)EL_HOST_NV_SIZE);
        close(fd);
        return false;
    }
    if (!read_all(fd, nv_mem, sizeof nv_mem)) {
        el_host_error("cannot read nvram %s: %s", path, strerror(errno));
        close(fd);
        return false;
    }
    nv_fd = fd;
    nv_path = path;
    return true;
}

/* Create nv_path holding `image` (atomically: FILE.tmp renamed over it). */
static bool create_file(const uint8_t *image)
{
    size_t n = strlen(nv_path);
    char *tmp = malloc(n + 5u), *dir;
    int fd, dfd;
    bool ok = false;

    if (tmp == NULL) {
        errno = ENOMEM;
        return false;
    }
    memcpy(tmp, nv_path, n);
    memcpy(tmp + n, ".tmp", 5u);
    fd = open(tmp, O_WRONLY | O_CREAT | O_TRUNC, 0666);
    if (fd >= 0) {
        ok = write_all(fd, image, EL_HOST_NV_SIZE, 0) && fsync(fd) == 0;
        if (close(fd) != 0)
            ok = false;
        if (ok)
            ok = rename(tmp, nv_path) == 0;
        if (!ok) {
            int err = errno;
            unlink(tmp);
            errno = err;
        }
    }
    free(tmp);
    if (!ok)
        return false;
    dir = directory_of(nv_path); /* make the rename itself durable */
    if (dir != NULL) {
        dfd = open(dir, O_RDONLY);
        if (dfd >= 0) {
            (void)fsync(dfd);
            close(dfd);
        }
        free(dir);
    }
    nv_fd = open(nv_path, O_RDWR);
    return nv_fd >= 0;
}

bool el_port_nv_read(uint16_t offset, void *data, uint16_t size)
{
    if ((uint32_t)offset + size > EL_HOST_NV_SIZE || (data == NULL && size != 0u))
        return false;
    if (size != 0u)
        memcpy(data, nv_mem + offset, size);
    return true;
}

bool el_port_nv_write(uint16_t offset, const void *data, uint16_t size)
{
    if ((uint32_t)offset + size > EL_HOST_NV_SIZE || (data == NULL && size != 0u))
        return false;
    if (size == 0u)
        return true;
    if (nv_path != NULL) {
        bool ok;
        if (nv_fd < 0) {
            static uint8_t image[EL_HOST_NV_SIZE];
            memcpy(image, nv_mem, sizeof image);
            memcpy(image + offset, data, size);
            ok = create_file(image);
        } else {
            ok = write_all(nv_fd, (const uint8_t *)data, size, (off_t)offset) && fsync(nv_fd) == 0;
        }
        if (!ok) {
            el_host_error("cannot write nvram %s: %s", nv_path, strerror(errno));
            return false;
        }
    }
    memcpy(nv_mem + offset, data, size);
    return true;
}
