// cairn-map: the map store's command line (see mapstore/map_cli.h).

#include "mapstore/map_cli.h"

int main(int argc, char** argv) { return cairn::mapstore::RunMapCli(argc, argv); }
