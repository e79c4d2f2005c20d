// Running a client message (messages.hpp) on a session: the one place where wire values become
// animator::Session calls, and where the session's errors get their wire names back.
#pragma once

#include "animator/session.hpp"
#include "server/messages.hpp"

namespace server {

/// Applies `message` to `session`: link names resolve against the session's model, positions
/// and rotations become Eigen values (rotations normalized). `hello` changes nothing (the
/// connection answers it). Call on the session's actor thread.
/// @throws ProtocolError "<type>.<field>: <rule>" (the session's own SessionError, renamed to
///         the message's fields; "<type>: <what>" when no field of the message is at fault).
///         The session is unchanged then.
void apply(animator::Session& session, const ClientMessage& message);

}  // namespace server
