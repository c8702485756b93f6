/* An impl-file actor for the interpreter tests: file-scope code, start and
 * stop handlers, state set by start. */
static int32_t twice(int32_t v)
{
    return (int32_t)(v * 2);
}

EL_START
{
    base = 1000;
}

EL_STEP
{
    base = base + 1;
    y = twice(base) + x;
}

EL_STOP
{
    base = 0;
}
