"""The one exception type of the tetrefine package."""

import grpc


class TetrefineError(Exception):
    """A refinement that did not happen, for whatever reason.

    Attributes:
      code: a ``grpc.StatusCode``. The server's status for a failed call (INVALID_ARGUMENT for
        malformed input, RESOURCE_EXHAUSTED for a server limit, DEADLINE_EXCEEDED, CANCELLED,
        UNAVAILABLE, ...); INVALID_ARGUMENT for input this package refused before sending it;
        UNIMPLEMENTED for a feature the generated protocol of this package does not have yet.
      details: the message alone: the server's, or ours. It names the argument or field and the
        index that is wrong.

    ``str(error)`` is ``"<CODE NAME>: <details>"``.
    """

    def __init__(self, code, details):
        self.code = code
        self.details = details
        super().__init__(f"{code.name}: {details}")

    @classmethod
    def from_rpc_error(cls, error):
        """The TetrefineError of a ``grpc.RpcError`` raised by a call."""
        code = error.code() if hasattr(error, "code") else grpc.StatusCode.UNKNOWN
        details = error.details() if hasattr(error, "details") else str(error)
        return cls(code, details or code.name.lower())


def invalid(argument, message):
    """A TetrefineError for caller input refused before anything is sent."""
    return TetrefineError(grpc.StatusCode.INVALID_ARGUMENT, f"{argument}: {message}")


def unsupported(argument, missing):
    """A TetrefineError for a feature the generated protocol lacks (`missing` names the field)."""
    return TetrefineError(
        grpc.StatusCode.UNIMPLEMENTED,
        f"{argument}: not in this package's tetrefine.v1 protocol (it has no {missing}); "
        "upgrade the tetrefine Python package to one generated from a proto that has it")
