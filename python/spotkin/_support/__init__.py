"""What every layer of the package shares: the argument checks at the boundary (``boundary``), the
per-sample status codes (``status``), rigid transforms (``transforms``), the thread and instruction-set
controls (``runtime``), the version (``version``) and the public paths of what public modules
export (``public``). Imports only the compiled core."""
