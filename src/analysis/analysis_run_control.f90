!> User control laws of a run (&controller law = 'user'): given by the program that uses
!> flexmor as a library, between run%load and run%execute. A law the program gives replaces
!> the one of the scene's `library`, which the model has from load on (model_build).
submodule (analysis_run) analysis_run_control
  use model_control, only: LAW_USER
  implicit none

contains

  !> A copy, not a pointer: the caller's object may go out of scope before execute, and every
  !> run (a sweep's cases) keeps its own. A law that must reach data of the caller holds a
  !> pointer to it itself (the C interface keeps its callback and user_data so).
  module procedure run_set_control_law
    integer :: k
    character(len=:), allocatable :: where
    where = 'group &controller ''' // label // ''''
    if (.not. allocated(this%dyn%model%controllers)) then
      call err%set(ERR_INPUT, 'set_control_law: no scene is loaded (call load first)')
      return
    end if
    do k = 1, size(this%dyn%model%controllers)
      associate (c => this%dyn%model%controllers(k))
        if (c%label /= label) cycle
        if (c%law_kind /= LAW_USER) then
          call err%set(ERR_INPUT, where // ': its law is not ''user'': a law cannot be set')
        else
          if (allocated(c%user_law)) deallocate(c%user_law)
          allocate(c%user_law, source=law)
        end if
        return
      end associate
    end do
    call err%set(ERR_INPUT, 'set_control_law: the scene has no &controller labelled ''' // &
      label // '''' // controller_labels(this))
  end procedure run_set_control_law

  !> Only a dynamic analysis runs the controllers; the others analyse the open-loop plant
  !> without them, so a law is needed only there.
  module procedure check_control_laws
    integer :: k
    if (.not. this%scene%dynamic%active .or. .not. allocated(this%dyn%model%controllers)) return
    do k = 1, size(this%dyn%model%controllers)
      associate (c => this%dyn%model%controllers(k))
        if (c%law_kind == LAW_USER .and. .not. allocated(c%user_law)) then
          call err%set(ERR_INPUT, 'group &controller ''' // c%label // ''': variable ' // &
            '''law'': ''user'' needs a control law: a shared library''s (''library'' and ' // &
            '''symbol'') or one from the program that runs the scene ' // &
            '(run%set_control_law, flexmor_set_controller)')
          return
        end if
      end associate
    end do
  end procedure check_control_laws

  !> ' (labels: 'a', 'b')', or '' without controllers: for the message of an unknown label.
  function controller_labels(this) result(text)
    type(run_t), intent(in) :: this
    character(len=:), allocatable :: text
    integer :: k
    text = ''
    do k = 1, size(this%dyn%model%controllers)
      text = text // trim(merge(' (labels: ', ',         ', k == 1)) // ' ''' // &
        this%dyn%model%controllers(k)%label // ''''
    end do
    if (len(text) > 0) text = text // ')'
  end function controller_labels
end submodule analysis_run_control
