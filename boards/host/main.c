/* EasyLab host board: the process entry point. */
#include "el_board.h"

int main(int argc, char **argv)
{
    el_run(argc, argv);
    return el_host_exit_status();
}
