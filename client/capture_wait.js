// How the page waits for a newly subscribed output's first capture: the
// server captures it from the next frame on, so the page reads the capture
// list, and reads it again after each frame, for a few frames at most.
//
// The frame waiter is set before each read: the frame that made the
// capture may land while the list is on its way (or before the wait even
// began), and with on-change rendering no other frame may follow.

/**
 * Resolves true once `listed()` (an async read of the capture list, true
 * when the output is in it) says so, false after `frames` frames or when
 * `nextFrame()` (a promise of the next frame: true, or false once the time
 * allowed is over) gives up.
 */
export async function awaitListed({ listed, nextFrame, frames }) {
  for (let seen = 0; ; seen++) {
    const next = seen < frames ? nextFrame() : null;
    if (await listed().catch(() => false)) return true;
    if (!next || !(await next)) return false;
  }
}
