"""What every layer of the package shares: the argument checks at the boundary (``boundary``), the
per-sample status codes (``status``), rigid transforms (``transforms``), the thread and instruction-set
controls (``runtime``) and the version (``version``). Imports only the compiled core."""
