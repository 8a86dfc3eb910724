//! Film grammar's diagnostic codes (`film::`): continuity and framing found on the directed
//! flight, compiled or flown. Add a code at the end; never rename one.

dronecine_diag::codes! {
    /// Film grammar's diagnostic codes (`film::`): continuity and framing found on the directed flight.
    pub enum FilmCode {
        CrossesLine => "film::crosses_line": "A cut puts the camera on the other side of the line of action between two actors.",
        JumpCut => "film::jump_cut": "A cut between two shots of the same subjects changes the camera's angle by less than 30° and the size by less than two steps.",
        ScreenDirection => "film::screen_direction": "A cut reverses the direction an actor walks across the screen.",
        OutOfFrame => "film::out_of_frame": "A framed actor leaves the frame during a shot.",
    }
}
