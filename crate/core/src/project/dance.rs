//! The dance edits of the project (spec §F, §G): a bar's candidates and feedback search, setting,
//! pinning and clearing a bar's move, Generate (and its takes and repeats), the dance settings
//! and the dance rendered as one clip. Each edit runs a pure command of [`crate::choreo`] on the
//! document's bars by stable [`MoveKey`] and commits the result as one undo step.

use super::*;

impl Project {
    /// The song's bars for a dance edit and the document to edit, its dance fitted to them
    /// (one entry per bar). Refused while a source's bytes are missing (the edit could not keep
    /// the moves it does not see).
    fn dance_edit_start(&mut self) -> Result<(Vec<Bar>, ProjectDoc), ProjectError> {
        if let Some(m) = self.missing.first() {
            if self.doc.sources.iter().any(|s| self.missing.iter().any(|m| m.hash == s.blob)) {
                return Err(ProjectError::Incomplete { count: self.missing.len(), first: m.what.clone() });
            }
        }
        let bars = self.song_bars()?;
        let mut doc = self.doc.clone();
        doc.dance.bars.resize(bars.len(), BarDoc::default());
        Ok((bars, doc))
    }

    /// The bar's current candidates, opening its search when none is open. Looking at a bar
    /// is not an edit: no undo step is recorded (the open search is kept and saved).
    pub fn candidates(&mut self, bar: usize) -> Result<Vec<MoveKey>, ProjectError> {
        let (bars, mut doc) = self.dance_edit_start()?;
        let b = crate::choreo::check_bar(&bars, bar)?;
        if self.derived.library().is_empty() {
            return Err(ChoreoError::EmptyLibrary.into());
        }
        let round = match &doc.dance.bars[bar].search {
            Some(s) => self.derived.session_of(s).round,
            None => {
                let session = crate::choreo::open_search(self.derived.library(), b, &doc.dance.settings)?;
                doc.dance.bars[bar].search = Some(self.derived.search_doc(&session));
                self.set_unrecorded(doc);
                session.round
            }
        };
        Ok(self.derived.keys_of(&round))
    }

    /// Search: likes `liked` (from the current round) and returns the next round.
    pub fn search(&mut self, bar: usize, liked: &[MoveKey]) -> Result<Vec<MoveKey>, ProjectError> {
        self.derived.update(&self.doc, &self.history.undo, &self.history.redo, &self.blobs);
        let liked = self.derived.indices_of(liked)?;
        let (bars, mut doc) = self.dance_edit_start()?;
        let b = crate::choreo::check_bar(&bars, bar)?;
        let mut session = doc.dance.bars[bar].search.as_ref().map(|s| self.derived.session_of(s)).ok_or(ChoreoError::NoSearch { bar })?;
        let round = crate::choreo::next_round(self.derived.library(), b, &mut session, &liked, &doc.dance.settings)?;
        doc.dance.bars[bar].search = Some(self.derived.search_doc(&session));
        self.commit(doc);
        Ok(self.derived.keys_of(&round))
    }

    /// Forgets the bar's search. Returns whether there was one.
    pub fn reset_search(&mut self, bar: usize) -> Result<bool, ProjectError> {
        let (bars, mut doc) = self.dance_edit_start()?;
        crate::choreo::check_bar(&bars, bar)?;
        let had = doc.dance.bars[bar].search.take().is_some();
        self.commit(doc);
        Ok(had)
    }

    /// Pins a move to a bar.
    pub fn set(&mut self, bar: usize, key: &MoveKey) -> Result<(), ProjectError> {
        self.derived.update(&self.doc, &self.history.undo, &self.history.redo, &self.blobs);
        self.derived.indices_of(std::slice::from_ref(key))?;
        let (bars, mut doc) = self.dance_edit_start()?;
        crate::choreo::check_bar(&bars, bar)?;
        let b = &mut doc.dance.bars[bar];
        (b.state, b.r#move, b.builtin_why) = (BarKind::Pinned, Some(key.clone()), None);
        self.commit(doc);
        Ok(())
    }

    /// Unpins a bar (its move stays, as generated).
    pub fn unpin(&mut self, bar: usize) -> Result<(), ProjectError> {
        let (bars, mut doc) = self.dance_edit_start()?;
        crate::choreo::check_bar(&bars, bar)?;
        let b = &mut doc.dance.bars[bar];
        if b.state == BarKind::Pinned && b.r#move.is_some() {
            b.state = BarKind::Generated;
        }
        self.commit(doc);
        Ok(())
    }

    /// Empties a bar (its search stays).
    pub fn clear(&mut self, bar: usize) -> Result<(), ProjectError> {
        let (bars, mut doc) = self.dance_edit_start()?;
        crate::choreo::check_bar(&bars, bar)?;
        let b = &mut doc.dance.bars[bar];
        (b.state, b.r#move, b.builtin_why) = (BarKind::Empty, None, None);
        self.commit(doc);
        Ok(())
    }

    /// Fills every bar that is not pinned (spec §G) by the pipeline of
    /// [`crate::choreo::generate`] at its default options. Pinned bars never change.
    pub fn generate(&mut self) -> Result<GenerateReport, ProjectError> {
        self.generate_with(&crate::choreo::GenerateOptions::default())
    }

    /// [`Project::generate`] with the pipeline's stages set by `options` (benches and tests turn
    /// a stage off to measure what it does); refused when an option is out of range.
    pub fn generate_with(&mut self, options: &crate::choreo::GenerateOptions) -> Result<GenerateReport, ProjectError> {
        let (bars, mut doc) = self.dance_edit_start()?;
        let d = &self.derived;
        let states: Vec<_> = doc.dance.bars.iter().map(|b| d.state_of(b)).collect();
        // Where the song's sections repeat, the repeated bars take their first occurrence's moves
        // (issue 26 item 2).
        let repeat_of = self.repeat_of_bars()?;
        let d = &self.derived;
        let (states, report, _) = crate::choreo::generate_states_with_repeats(d.library(), &bars, &states, doc.dance.settings.fill, options, &repeat_of)?;
        for (i, (b, state)) in doc.dance.bars.iter_mut().zip(states).enumerate() {
            if !matches!(state, crate::choreo::BarState::Pinned { .. }) {
                let filled = state.segment().is_some();
                *b = d.bar_doc(state, b.search.take());
                // Why the bar is built-in, kept with it (schema 7).
                b.builtin_why = report.builtin_why.get(i).copied().flatten().filter(|_| filled);
            }
        }
        doc.dance.take = options.take;
        self.commit(doc);
        Ok(report)
    }

    /// Fills every bar that is not pinned with take `take` of Generate (issue 26: take 0 is
    /// [`Project::generate`]'s dance, each further take a different dance of comparable cost,
    /// [`crate::choreo::generate::takes`]) and keeps the take's number with its bars;
    /// one undo step. A take above [`crate::choreo::generate::MAX_TAKE`] is refused.
    pub fn generate_take(&mut self, take: u32) -> Result<GenerateReport, ProjectError> {
        self.generate_with(&crate::choreo::GenerateOptions { take, ..crate::choreo::GenerateOptions::default() })
    }

    /// The song's sections (`music::sections` at its default options over the project's grid
    /// and loudness envelope: the one analysis the dance's repeats and the video's director
    /// camera use); None without a song.
    pub fn sections(&mut self) -> Result<Option<crate::music::Sections>, ProjectError> {
        let Some(song) = self.doc.song.as_ref() else { return Ok(None) };
        self.derived.update(&self.doc, &self.history.undo, &self.history.redo, &self.blobs);
        let grid = match self.derived.grid() {
            None => return Ok(None),
            Some(Err(e)) => return Err(e.clone()),
            Some(Ok(g)) => g,
        };
        let bytes = self.blobs.get(&song.envelope).ok_or_else(|| ProjectError::Incomplete { count: 1, first: format!("the envelope of {}", song.file_name) })?;
        let env = decode_envelope(bytes)?;
        Ok(Some(crate::music::sections(grid, &env, &crate::music::SectionOptions::default())?))
    }

    /// Per bar of the song, the earlier bar it repeats: where the song's sections repeat
    /// ([`Project::sections`], `music::Sections::repeat_of_bars`), with the person's marks laid
    /// over them ([`Project::repeats`]): what Generate gives the same move, and what the bar's
    /// note says ("repeats bar N"). Empty without a song.
    pub fn repeat_of_bars(&mut self) -> Result<Vec<Option<usize>>, ProjectError> {
        Ok(self.repeats()?.into_iter().map(|r| r.map(|r| r.of_bar)).collect())
    }

    /// Per bar of the song, what it repeats (the first occurrence's bar, and whether the person
    /// marked it): the analysis's repeats with the marks laid over them in order
    /// ([`repeats::resolve`]). Empty without a song.
    pub fn repeats(&mut self) -> Result<Vec<Option<BarRepeat>>, ProjectError> {
        let n = match self.derived().grid() {
            Some(Ok(g)) => g.bars.len(),
            _ => 0,
        };
        let found = self.sections()?.map(|s| s.repeat_of_bars(n)).unwrap_or_default();
        Ok(repeats::resolve(&found, &self.doc.dance.repeats, n))
    }

    /// The runs of repeated bars ([`Project::repeats`] as ranges): what the song strip shows
    /// and offers to remove.
    pub fn repeat_runs(&mut self) -> Result<Vec<RepeatRun>, ProjectError> {
        Ok(repeats::runs(&self.repeats()?))
    }

    /// Marks bars `range` as repeating the earlier bars `of` (issue 26: the person hears a
    /// repeat the analysis missed): Generate then gives them the same moves. One undo step;
    /// refused, with nothing changed, when a range is empty or out of the song, the two differ
    /// in length, overlap, or `of` is not earlier.
    pub fn mark_repeat(&mut self, range: BarRange, of: BarRange) -> Result<(), ProjectError> {
        let (bars, mut doc) = self.dance_edit_start()?;
        doc.dance.repeats = repeats::with_mark(&doc.dance.repeats, range, of, bars.len())?;
        self.commit(doc);
        Ok(())
    }

    /// Removes the repeat holding bar `bar` (found by the analysis or marked), its whole run:
    /// Generate then fills those bars on their own. One undo step; refused when the bar repeats
    /// nothing. Returns the run removed.
    pub fn remove_repeat(&mut self, bar: usize) -> Result<RepeatRun, ProjectError> {
        let n = self.song_bars()?.len();
        let found = self.sections()?.map(|s| s.repeat_of_bars(n)).unwrap_or_default();
        let (bars, mut doc) = self.dance_edit_start()?;
        let (marks, run) = repeats::without_repeat(&found, &doc.dance.repeats, bar, bars.len())?;
        doc.dance.repeats = marks;
        self.commit(doc);
        Ok(run)
    }

    /// Per bar, the built-in move the Generate that filled it chose there and why it is
    /// built-in though the person's moves come first (issue 26; [`crate::choreo::mark_builtin_why`]
    /// says it on the bar's note while the bar still holds that move). Kept with the bars
    /// ([`BarDoc::builtin_why`], schema 7): the same after save/reopen and through undo; `None`
    /// for a bar Generate did not make built-in, or whose move is not in the library.
    pub fn builtin_why(&mut self) -> Vec<Option<(usize, crate::choreo::BuiltinWhy)>> {
        self.derived.update(&self.doc, &self.history.undo, &self.history.redo, &self.blobs);
        let d = &self.derived;
        self.doc.dance.bars.iter().map(|b| Some((d.state_of(b).segment()?, b.builtin_why?))).collect()
    }

    /// The take of Generate the dance's generated bars come from (0 until "another take").
    pub fn take(&self) -> u32 {
        self.doc.dance.take
    }

    /// Changes one setting of the search or the filling; refused, with nothing changed, when
    /// its value is out of range. Undoable.
    pub fn set_setting(&mut self, setting: Setting) -> Result<(), ProjectError> {
        let (_, mut doc) = self.dance_edit_start()?;
        doc.dance.settings.apply(setting)?;
        self.commit(doc);
        Ok(())
    }

    /// ρ of spec §F eq. 1, in 0..=1.
    pub fn set_rho(&mut self, rho: f32) -> Result<(), ProjectError> {
        self.set_setting(Setting::Rho(rho))
    }

    /// Weight of the music term of the filling, in 0..=100.
    pub fn set_music_weight(&mut self, w: f32) -> Result<(), ProjectError> {
        self.set_setting(Setting::MusicWeight(w))
    }

    /// Weight of the beat term of the filling (segments whose counts fall on their kinetic
    /// beats; 0 turns it off).
    pub fn set_beat_weight(&mut self, w: f32) -> Result<(), ProjectError> {
        self.set_setting(Setting::BeatWeight(w))
    }

    /// Preference of the filling for the person's imported moves that fit the beat over
    /// built-in ones (0: none).
    pub fn set_own_moves_preference(&mut self, w: f32) -> Result<(), ProjectError> {
        self.set_setting(Setting::OwnMovesPreference(w))
    }

    /// Which moves Generate fills the open bars with (issue 26: the person's own first, mixed,
    /// or built-in only); one undo step.
    pub fn set_moves_source(&mut self, source: crate::choreo::MovesSource) -> Result<(), ProjectError> {
        self.set_setting(Setting::MovesSource(source))
    }

    /// The filling's weights in force.
    pub fn fill_weights(&self) -> FillWeights {
        self.doc.dance.settings.fill
    }

    /// The whole dance as one canonical clip; frame 0 is song time 0. Bars whose move cannot
    /// be found (a missing source) stand neutral.
    pub fn render_dance(&mut self, options: &crate::choreo::RenderOptions) -> Result<Clip, ProjectError> {
        Ok(self.render_dance_switched(options)?.0)
    }

    /// [`Project::render_dance`], with where each join falls (song seconds of the switch into
    /// each bar after the first, [`crate::choreo::render_switched`]): what the readouts measure
    /// the joins at ([`crate::choreo::dance_quality_switched`]).
    pub fn render_dance_switched(&mut self, options: &crate::choreo::RenderOptions) -> Result<(Clip, Vec<f32>), ProjectError> {
        let bars = self.song_bars()?;
        let d = &self.derived;
        let lib = d.library();
        let choices: Vec<Option<usize>> = self.doc.dance.bars.iter().map(|b| d.state_of(b).segment().filter(|&s| s < lib.len())).collect();
        let choices: Vec<Option<usize>> = (0..bars.len()).map(|i| choices.get(i).copied().flatten()).collect();
        let (mut clip, switches) = crate::choreo::render_switched(lib, &bars, &choices, options);
        clip.name = "Dance".into();
        clip.source = "choreography".into();
        Ok((clip, switches))
    }
}
