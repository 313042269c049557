"""The client's one error type."""


class ClientError(Exception):
    """A named error: a bad port, a transport that failed, a bad request, file or protocol description.

    The command line prints it as ``osc_client: MESSAGE`` and exits with status 2.
    """
