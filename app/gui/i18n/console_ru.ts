<?xml version='1.0' encoding='utf-8'?>
<TS version="2.1" language="ru_RU">
<context>
    <name>ConsoleWindow</name>
    <message>
        <source>Run-time &amp;trends…</source>
        <translation>&amp;Тренды…</translation>
    </message>
    <message>
        <source>Open journal &amp;viewer…</source>
        <translation>Открыть &amp;просмотр журнала…</translation>
    </message>
    <message>
        <source>&amp;Station</source>
        <translation>&amp;Станция</translation>
    </message>
    <message>
        <source>&amp;Program…</source>
        <translation>&amp;Программа…</translation>
    </message>
    <message>
        <source>&amp;View</source>
        <translation>&amp;Вид</translation>
    </message>
    <message>
        <source>The station's files are not loaded yet</source>
        <translation>Файлы станции ещё не загружены</translation>
    </message>
    <message>
        <source>Alarms</source>
        <translation>Аварии</translation>
    </message>
    <message>
        <source>Alarms — {0} unacknowledged</source>
        <translation>Аварии — неквитированных: {0}</translation>
    </message>
    <message>
        <source>Confirm</source>
        <translation>Подтверждение</translation>
    </message>
    <message>
        <source>cancelled</source>
        <translation>отменено</translation>
    </message>
    <message>
        <source>No unacknowledged alarms</source>
        <translation>Нет неквитированных аварий</translation>
    </message>
    <message>
        <source>station unreachable: {0}; reconnecting</source>
        <translation>станция недоступна: {0}; переподключение</translation>
    </message>
    <message>
        <source>Refused: </source>
        <translation>Отказано: </translation>
    </message>
    <message>
        <source>Acknowledge</source>
        <translation>Квитировать</translation>
    </message>
    <message>
        <source>Acknowledge all</source>
        <translation>Квитировать все</translation>
    </message>
    <message>
        <source>The station serves no forms.</source>
        <translation>Станция не передаёт мнемосхем.</translation>
    </message>
    <message>
        <source>Form problems</source>
        <translation>Ошибки форм</translation>
    </message>
    <message>
        <source>No forms</source>
        <translation>Нет форм</translation>
    </message>
</context>
<context>
    <name>AlarmBanner</name>
    <message>
        <source>Acknowledge</source>
        <translation>Квитировать</translation>
    </message>
    <message>
        <source>Acknowledge all</source>
        <translation>Квитировать все</translation>
    </message>
    <message>
        <source>{0} unacknowledged</source>
        <translation>неквитированных: {0}</translation>
    </message>
</context>
<context>
    <name>AlarmSummary</name>
    <message>
        <source>listed alarms of priority {0} ({1})</source>
        <translation>аварий приоритета {0} в списке ({1})</translation>
    </message>
    <message>
        <source>Filter: alarm, text or state</source>
        <translation>Фильтр: авария, текст или состояние</translation>
    </message>
    <message>
        <source>Acknowledge</source>
        <translation>Квитировать</translation>
    </message>
    <message>
        <source>Acknowledge all</source>
        <translation>Квитировать все</translation>
    </message>
    <message>
        <source>Shelve…</source>
        <translation>Отложить…</translation>
    </message>
    <message>
        <source>Unshelve</source>
        <translation>Вернуть</translation>
    </message>
    <message>
        <source>Silence</source>
        <translation>Без звука</translation>
    </message>
    <message>
        <source>Stop the sound; the alarms stay unacknowledged</source>
        <translation>Выключить звук; аварии остаются неквитированными</translation>
    </message>
    <message>
        <source>Shelve</source>
        <translation>Отложить</translation>
    </message>
    <message>
        <source>Select the alarm to shelve first.</source>
        <translation>Сначала выберите аварию, которую нужно отложить.</translation>
    </message>
    <message>
        <source>Acknowledge {0}</source>
        <translation>Квитировать {0}</translation>
    </message>
    <message>
        <source>Shelve {0}</source>
        <translation>Отложить {0}</translation>
    </message>
    <message>
        <source>Unshelve {0}</source>
        <translation>Вернуть {0}</translation>
    </message>
</context>
<context>
    <name>AlarmTableModel</name>
    <message>
        <source>Priority</source>
        <translation>Приоритет</translation>
    </message>
    <message>
        <source>Time</source>
        <translation>Время</translation>
    </message>
    <message>
        <source>Alarm</source>
        <translation>Авария</translation>
    </message>
    <message>
        <source>State</source>
        <translation>Состояние</translation>
    </message>
    <message>
        <source>Text</source>
        <translation>Текст</translation>
    </message>
    <message>
        <source>shelved by {0} until {1}: {2}</source>
        <translation>отложена ({0}) до {1}: {2}</translation>
    </message>
    <message>
        <source>Value at change</source>
        <translation>Значение при изменении</translation>
    </message>
    <message>
        <source>The value when the alarm last changed state, not the value now</source>
        <translation>Значение в момент последнего изменения состояния аварии, а не текущее</translation>
    </message>
</context>
<context>
    <name>ColorEditor</name>
    <message>
        <source>Pick a colour</source>
        <translation>Выбрать цвет</translation>
    </message>
    <message>
        <source>Colour</source>
        <translation>Цвет</translation>
    </message>
</context>
<context>
    <name>ComboEditor</name>
    <message>
        <source>(default)</source>
        <translation>(по умолчанию)</translation>
    </message>
</context>
<context>
    <name>DateTimeWidget</name>
    <message>
        <source>since start {0}</source>
        <translation>с пуска {0}</translation>
    </message>
</context>
<context>
    <name>DesignerWindow</name>
    <message>
        <source>, {0} warning(s)</source>
        <translation>, предупреждений: {0}</translation>
    </message>
    <message>
        <source>{0} problem(s): see Problems</source>
        <translation>проблем: {0} (см. «Проблемы»)</translation>
    </message>
    <message>
        <source>No problems</source>
        <translation>Проблем нет</translation>
    </message>
    <message>
        <source>&amp;Arrange</source>
        <translation>&amp;Упорядочить</translation>
    </message>
    <message>
        <source>&amp;Copy</source>
        <translation>&amp;Копировать</translation>
    </message>
    <message>
        <source>&amp;Delete</source>
        <translation>&amp;Удалить</translation>
    </message>
    <message>
        <source>&amp;Edit</source>
        <translation>&amp;Правка</translation>
    </message>
    <message>
        <source>&amp;File</source>
        <translation>&amp;Файл</translation>
    </message>
    <message>
        <source>&amp;New form…</source>
        <translation>&amp;Новая форма…</translation>
    </message>
    <message>
        <source>&amp;Paste</source>
        <translation>&amp;Вставить</translation>
    </message>
    <message>
        <source>&amp;Preview live</source>
        <translation>&amp;Живой просмотр</translation>
    </message>
    <message>
        <source>&amp;Redo {0}</source>
        <translation>&amp;Повторить {0}</translation>
    </message>
    <message>
        <source>&amp;Redo</source>
        <translation>&amp;Повторить</translation>
    </message>
    <message>
        <source>&amp;Save</source>
        <translation>&amp;Сохранить</translation>
    </message>
    <message>
        <source>&amp;Undo {0}</source>
        <translation>&amp;Отменить {0}</translation>
    </message>
    <message>
        <source>&amp;Undo</source>
        <translation>&amp;Отменить</translation>
    </message>
    <message>
        <source>Actual size</source>
        <translation>Реальный размер</translation>
    </message>
    <message>
        <source>Add &amp;element</source>
        <translation>Добавить &amp;элемент</translation>
    </message>
    <message>
        <source>Cu&amp;t</source>
        <translation>Вы&amp;резать</translation>
    </message>
    <message>
        <source>Designer</source>
        <translation>Конструктор</translation>
    </message>
    <message>
        <source>Discard the unsaved changes of this form?</source>
        <translation>Отбросить несохранённые изменения формы?</translation>
    </message>
    <message>
        <source>Distribute horizontally</source>
        <translation>Распределить по горизонтали</translation>
    </message>
    <message>
        <source>Distribute vertically</source>
        <translation>Распределить по вертикали</translation>
    </message>
    <message>
        <source>Elements</source>
        <translation>Элементы</translation>
    </message>
    <message>
        <source>Form designer</source>
        <translation>Конструктор форм</translation>
    </message>
    <message>
        <source>Forms (*.hmi)</source>
        <translation>Формы (*.hmi)</translation>
    </message>
    <message>
        <source>Forms of the station</source>
        <translation>Формы станции</translation>
    </message>
    <message>
        <source>Grid size…</source>
        <translation>Шаг сетки…</translation>
    </message>
    <message>
        <source>Grid step, pixels:</source>
        <translation>Шаг сетки, пикселей:</translation>
    </message>
    <message>
        <source>Grid</source>
        <translation>Сетка</translation>
    </message>
    <message>
        <source>New form</source>
        <translation>Новая форма</translation>
    </message>
    <message>
        <source>No station with a Modbus server beside this form</source>
        <translation>Рядом с формой нет станции с сервером Modbus</translation>
    </message>
    <message>
        <source>Open form</source>
        <translation>Открыть форму</translation>
    </message>
    <message>
        <source>Problems</source>
        <translation>Проблемы</translation>
    </message>
    <message>
        <source>Properties</source>
        <translation>Свойства</translation>
    </message>
    <message>
        <source>Save &amp;as…</source>
        <translation>Сохранить &amp;как…</translation>
    </message>
    <message>
        <source>Save form as</source>
        <translation>Сохранить форму как</translation>
    </message>
    <message>
        <source>Saved {0}</source>
        <translation>Сохранено: {0}</translation>
    </message>
    <message>
        <source>Select &amp;all</source>
        <translation>Выделить &amp;всё</translation>
    </message>
    <message>
        <source>Show grid</source>
        <translation>Показывать сетку</translation>
    </message>
    <message>
        <source>Snap to &amp;grid</source>
        <translation>Привязка к &amp;сетке</translation>
    </message>
    <message>
        <source>Tags</source>
        <translation>Теги</translation>
    </message>
    <message>
        <source>The form was not saved: {0}</source>
        <translation>Форма не сохранена: {0}</translation>
    </message>
    <message>
        <source>Zoom in</source>
        <translation>Увеличить</translation>
    </message>
    <message>
        <source>Zoom out</source>
        <translation>Уменьшить</translation>
    </message>
    <message>
        <source>{0} - NetPlc form designer</source>
        <translation>{0} — конструктор форм NetPlc</translation>
    </message>
    <message>
        <source>{0} problem(s), see Problems: the station will not open the form. Save anyway?</source>
        <translation>Проблем: {0} (см. «Проблемы»): станция не откроет эту форму. Всё равно сохранить?</translation>
    </message>
    <message>
        <source>The station serves Modbus RTU on a serial port; the preview reads Modbus TCP</source>
        <translation>Станция отдаёт Modbus RTU через последовательный порт, а просмотр читает Modbus TCP</translation>
    </message>
    <message>
        <source>Align left</source>
        <translation>Выровнять по левому краю</translation>
    </message>
    <message>
        <source>Align right</source>
        <translation>Выровнять по правому краю</translation>
    </message>
    <message>
        <source>Align top</source>
        <translation>Выровнять по верху</translation>
    </message>
    <message>
        <source>Align bottom</source>
        <translation>Выровнять по низу</translation>
    </message>
    <message>
        <source>Centre horizontally</source>
        <translation>Центрировать по горизонтали</translation>
    </message>
    <message>
        <source>Centre vertically</source>
        <translation>Центрировать по вертикали</translation>
    </message>
    <message>
        <source>Bring to front</source>
        <translation>На передний план</translation>
    </message>
    <message>
        <source>Raise</source>
        <translation>Поднять</translation>
    </message>
    <message>
        <source>Lower</source>
        <translation>Опустить</translation>
    </message>
    <message>
        <source>Send to back</source>
        <translation>На задний план</translation>
    </message>
    <message>
        <source>&amp;Close</source>
        <translation>&amp;Закрыть</translation>
    </message>
    <message>
        <source>&amp;Open…</source>
        <translation>&amp;Открыть…</translation>
    </message>
    <message>
        <source>&amp;View</source>
        <translation>&amp;Вид</translation>
    </message>
</context>
<context>
    <name>DiscreteWidget</name>
    <message>
        <source>(indication off)</source>
        <translation>(индикация выключена)</translation>
    </message>
    <message>
        <source> (click to toggle)</source>
        <translation> (щелчок переключает)</translation>
    </message>
</context>
<context>
    <name>FontEditor</name>
    <message>
        <source>(default)</source>
        <translation>(по умолчанию)</translation>
    </message>
    <message>
        <source>Back to the default font</source>
        <translation>Вернуть шрифт по умолчанию</translation>
    </message>
    <message>
        <source>Font</source>
        <translation>Шрифт</translation>
    </message>
</context>
<context>
    <name>HealthDialog</name>
    <message>
        <source>Alarm-system health</source>
        <translation>Состояние системы аварийной сигнализации</translation>
    </message>
    <message>
        <source>Day:</source>
        <translation>День:</translation>
    </message>
    <message>
        <source>reading the archive…</source>
        <translation>чтение архива…</translation>
    </message>
    <message>
        <source>no alarm-system health: {0}</source>
        <translation>нет данных о системе аварийной сигнализации: {0}</translation>
    </message>
    <message>
        <source>{0}: cannot read the archive: {1}</source>
        <translation>{0}: архив не читается: {1}</translation>
    </message>
</context>
<context>
    <name>HealthStrip</name>
    <message>
        <source>Details…</source>
        <translation>Подробно…</translation>
    </message>
    <message>
        <source>Station problems</source>
        <translation>Неисправности станции</translation>
    </message>
</context>
<context>
    <name>JournalDock</name>
    <message>
        <source>Journal — today</source>
        <translation>Журнал — сегодня</translation>
    </message>
    <message>
        <source>Events only (messages, operator actions, system)</source>
        <translation>Только события (сообщения, действия операторов, система)</translation>
    </message>
    <message>
        <source>no archive yet</source>
        <translation>архива ещё нет</translation>
    </message>
    <message>
        <source>archive unreadable: {0}</source>
        <translation>архив не читается: {0}</translation>
    </message>
    <message>
        <source>, newest {0} shown</source>
        <translation>, показаны последние {0}</translation>
    </message>
    <message>
        <source>{0} records today</source>
        <translation>{0} записей сегодня</translation>
    </message>
</context>
<context>
    <name>LoginDialog</name>
    <message>
        <source>Log in</source>
        <translation>Вход</translation>
    </message>
    <message>
        <source>User:</source>
        <translation>Пользователь:</translation>
    </message>
    <message>
        <source>Password:</source>
        <translation>Пароль:</translation>
    </message>
    <message>
        <source>This station has no users yet: main.py users add NAME --role ROLE</source>
        <translation>У этой станции ещё нет пользователей: main.py users add ИМЯ --role РОЛЬ</translation>
    </message>
</context>
<context>
    <name>MainWindow</name>
    <message>
        <source>Run-time &amp;trends…</source>
        <translation>&amp;Тренды…</translation>
    </message>
    <message>
        <source>No unacknowledged alarms</source>
        <translation>Нет неквитированных аварий</translation>
    </message>
    <message>
        <source>&amp;Station</source>
        <translation>&amp;Станция</translation>
    </message>
    <message>
        <source>&amp;Run NetPlc…</source>
        <translation>&amp;Запустить NetPlc…</translation>
    </message>
    <message>
        <source>&amp;Stop NetPlc…</source>
        <translation>&amp;Остановить NetPlc…</translation>
    </message>
    <message>
        <source>&amp;Log in / switch user…</source>
        <translation>&amp;Вход / смена пользователя…</translation>
    </message>
    <message>
        <source>Log &amp;out</source>
        <translation>В&amp;ыйти из системы</translation>
    </message>
    <message>
        <source>&amp;Users…</source>
        <translation>&amp;Пользователи…</translation>
    </message>
    <message>
        <source>Open journal &amp;viewer…</source>
        <translation>Открыть &amp;просмотр журнала…</translation>
    </message>
    <message>
        <source>&amp;Quit…</source>
        <translation>В&amp;ыход…</translation>
    </message>
    <message>
        <source>&amp;View</source>
        <translation>&amp;Вид</translation>
    </message>
    <message>
        <source>&amp;Collapse docks</source>
        <translation>&amp;Свернуть панели</translation>
    </message>
    <message>
        <source>&amp;Full screen</source>
        <translation>&amp;Полный экран</translation>
    </message>
    <message>
        <source>Fit &amp;width</source>
        <translation>По &amp;ширине</translation>
    </message>
    <message>
        <source>Fit &amp;window</source>
        <translation>По &amp;окну</translation>
    </message>
    <message>
        <source>&amp;100 %</source>
        <translation>&amp;100 %</translation>
    </message>
    <message>
        <source>Zoom &amp;in</source>
        <translation>&amp;Крупнее</translation>
    </message>
    <message>
        <source>Zoom &amp;out</source>
        <translation>&amp;Мельче</translation>
    </message>
    <message>
        <source>&amp;Help</source>
        <translation>&amp;Справка</translation>
    </message>
    <message>
        <source>&amp;About</source>
        <translation>&amp;О программе</translation>
    </message>
    <message>
        <source>This station has no HMIload folder.</source>
        <translation>У этой станции нет папки HMIload.</translation>
    </message>
    <message>
        <source>No forms</source>
        <translation>Нет форм</translation>
    </message>
    <message>
        <source>Form problems</source>
        <translation>Ошибки форм</translation>
    </message>
    <message>
        <source>No .hmi forms in {0}.</source>
        <translation>В {0} нет форм .hmi.</translation>
    </message>
    <message>
        <source>Zoom: </source>
        <translation>Масштаб: </translation>
    </message>
    <message>
        <source>Acknowledge</source>
        <translation>Квитировать</translation>
    </message>
    <message>
        <source>Refused: </source>
        <translation>Отказано: </translation>
    </message>
    <message>
        <source>Confirm</source>
        <translation>Подтверждение</translation>
    </message>
    <message>
        <source>cancelled</source>
        <translation>отменено</translation>
    </message>
    <message>
        <source>Run NetPlc</source>
        <translation>Запуск NetPlc</translation>
    </message>
    <message>
        <source>Run the NetPlc program? Its chains act on the plant from the next scan.</source>
        <translation>Запустить программу NetPlc? Её цепи начнут действовать на объект со следующего цикла.</translation>
    </message>
    <message>
        <source>Stop NetPlc</source>
        <translation>Останов NetPlc</translation>
    </message>
    <message>
        <source>Stop the NetPlc program? Exchange, archive and forms keep running, but the program's chains are no longer executed.</source>
        <translation>Остановить программу NetPlc? Обмен, архив и формы продолжат работу, но цепи программы выполняться не будут.</translation>
    </message>
    <message>
        <source>Quit</source>
        <translation>Выход</translation>
    </message>
    <message>
        <source>Quit NetPlc Station? The NetPlc program, the exchange with the nodes and the archive stop.</source>
        <translation>Завершить NetPlc Station? Программа NetPlc, обмен с узлами и архив будут остановлены.</translation>
    </message>
    <message>
        <source>Users</source>
        <translation>Пользователи</translation>
    </message>
    <message>
        <source>NetPlc Station {0}: the PC runtime for CPU-165 PLC networks (FregatServer).</source>
        <translation>NetPlc Station {0}: среда исполнения ПК для сетей контроллеров CPU-165 (FregatServer).</translation>
    </message>
    <message>
        <source>Station: {0}</source>
        <translation>Станция: {0}</translation>
    </message>
    <message>
        <source>Alarms</source>
        <translation>Аварии</translation>
    </message>
    <message>
        <source>Alarms — {0} unacknowledged</source>
        <translation>Аварии — неквитированных: {0}</translation>
    </message>
    <message>
        <source>Simulated node {0} answers</source>
        <translation>Имитируемый узел {0} отвечает</translation>
    </message>
    <message>
        <source>Untick to pull the node's cable: its values go comm-fail, their alarms come</source>
        <translation>Снимите флажок, чтобы «выдернуть кабель» узла: его значения получают признак «нет связи», приходят их аварии</translation>
    </message>
    <message>
        <source>Alarm-system &amp;health…</source>
        <translation>Состояние &amp;аварийной сигнализации…</translation>
    </message>
    <message>
        <source>&amp;Program…</source>
        <translation>&amp;Программа…</translation>
    </message>
</context>
<context>
    <name>Palette</name>
    <message>
        <source>pulses on OutAddr: scan mod Period = Phase (Fig. 2.4.3)</source>
        <translation>импульсы на OutAddr: скан mod Period = Phase (рис. 2.4.3)</translation>
    </message>
    <message>
        <source>a sync generator enabled by Ainput</source>
        <translation>генератор синхронизации, разрешаемый Ainput</translation>
    </message>
    <message>
        <source>a bit as text, image and lamp; a button when Enabled</source>
        <translation>бит как текст, картинка, лампа; кнопка при Enabled</translation>
    </message>
    <message>
        <source>a bit with colours per state</source>
        <translation>бит с цветами по состояниям</translation>
    </message>
    <message>
        <source>its state only while EnableAddr is 1</source>
        <translation>состояние только пока EnableAddr = 1</translation>
    </message>
    <message>
        <source>cycles ImageFirst..ImageLast while the bit is 1</source>
        <translation>перебирает ImageFirst..ImageLast, пока бит = 1</translation>
    </message>
    <message>
        <source>a tag's value with its unit: digital, bar, dial, graph</source>
        <translation>значение тега с единицей: цифры, полоса, шкала, график</translation>
    </message>
    <message>
        <source>the operator's setpoint, converted and written</source>
        <translation>уставка оператора: пересчитывается и записывается</translation>
    </message>
    <message>
        <source>a picture from the form's folder</source>
        <translation>картинка из папки формы</translation>
    </message>
    <message>
        <source>a caption</source>
        <translation>надпись</translation>
    </message>
    <message>
        <source>a bit trend, one sample per scan</source>
        <translation>тренд бита, одна точка за скан</translation>
    </message>
    <message>
        <source>the archive's records of a day</source>
        <translation>записи архива за день</translation>
    </message>
    <message>
        <source>time, date and the time since start</source>
        <translation>время, дата и время с пуска</translation>
    </message>
    <message>
        <source>{0}: {1}
Drag onto the form, or double-click to add</source>
        <translation>{0}: {1}
Перетащите на форму или дважды щёлкните, чтобы добавить</translation>
    </message>
</context>
<context>
    <name>Preview</name>
    <message>
        <source>Preview live: {0}</source>
        <translation>Живой просмотр: {0}</translation>
    </message>
    <message>
        <source>Preview: {0}</source>
        <translation>Просмотр: {0}</translation>
    </message>
</context>
<context>
    <name>ProblemsPane</name>
    <message>
        <source>warning: {0}</source>
        <translation>предупреждение: {0}</translation>
    </message>
</context>
<context>
    <name>PropertyPanel</name>
    <message>
        <source>Form {0}</source>
        <translation>Форма {0}</translation>
    </message>
    <message>
        <source>{0} elements</source>
        <translation>элементов: {0}</translation>
    </message>
</context>
<context>
    <name>ShelveDialog</name>
    <message>
        <source>Shelve {0}</source>
        <translation>Отложить {0}</translation>
    </message>
    <message>
        <source> min</source>
        <translation> мин</translation>
    </message>
    <message>
        <source>why (required)</source>
        <translation>причина (обязательно)</translation>
    </message>
    <message>
        <source>Duration</source>
        <translation>Длительность</translation>
    </message>
    <message>
        <source>Reason</source>
        <translation>Причина</translation>
    </message>
    <message>
        <source>Maintenance of the instrument</source>
        <translation>Обслуживание прибора</translation>
    </message>
    <message>
        <source>Instrument faulty, repair requested</source>
        <translation>Прибор неисправен, ремонт заказан</translation>
    </message>
    <message>
        <source>Nuisance: chattering alarm</source>
        <translation>Ложная: дребезг аварии</translation>
    </message>
    <message>
        <source>Start-up or shut-down of the unit</source>
        <translation>Пуск или останов установки</translation>
    </message>
    <message>
        <source>Known condition, under observation</source>
        <translation>Известное состояние, под наблюдением</translation>
    </message>
    <message>
        <source>Choose a usual reason…</source>
        <translation>Выберите типовую причину…</translation>
    </message>
    <message>
        <source>Give the reason for shelving: it is journaled with your name.</source>
        <translation>Укажите причину отключения: она записывается в журнал с вашим именем.</translation>
    </message>
</context>
<context>
    <name>StationStatusBar</name>
    <message>
        <source>Consoles {0}</source>
        <translation>Пульты {0}</translation>
    </message>
    <message>
        <source>NetPlc: {0}</source>
        <translation>NetPlc: {0}</translation>
    </message>
    <message>
        <source>Scan {0:.2f} ms  max {1:.2f} ms</source>
        <translation>Цикл {0:.2f} мс  макс. {1:.2f} мс</translation>
    </message>
    <message>
        <source>{0} scans, mean {1:.3f} ms, {2} overruns</source>
        <translation>{0} циклов, в среднем {1:.3f} мс, {2} превышений</translation>
    </message>
    <message>
        <source>Tick {0} ms</source>
        <translation>Такт {0} мс</translation>
    </message>
    <message>
        <source>NetSyncTime {0} ms; {1} scans took longer</source>
        <translation>NetSyncTime {0} мс; дольше шли {1} циклов</translation>
    </message>
    <message>
        <source>Nodes {0}/{1}</source>
        <translation>Узлы {0}/{1}</translation>
    </message>
    <message>
        <source>Archive {0} records</source>
        <translation>Архив: {0} записей</translation>
    </message>
    <message>
        <source>{0} waiting, {1} lost</source>
        <translation>{0} в очереди, {1} потеряно</translation>
    </message>
    <message>
        <source>NetPlc memory served over Modbus TCP</source>
        <translation>Память NetPlc доступна по Modbus TCP</translation>
    </message>
    <message>
        <source>NetPlc memory served over Modbus RTU</source>
        <translation>Память NetPlc доступна по Modbus RTU</translation>
    </message>
    <message>
        <source>Modbus off</source>
        <translation>Modbus выключен</translation>
    </message>
    <message>
        <source>running</source>
        <translation>работает</translation>
    </message>
    <message>
        <source>stopped</source>
        <translation>остановлен</translation>
    </message>
    <message>
        <source>halted</source>
        <translation>остановлен (HLT)</translation>
    </message>
    <message>
        <source>idle</source>
        <translation>простой</translation>
    </message>
    <message>
        <source>F: {0} forced</source>
        <translation>Ф: форсировано {0}</translation>
    </message>
    <message>
        <source>forces in effect: force &gt; program &gt; live (Station -&gt; Program)</source>
        <translation>действуют форсирования: форсирование &gt; программа &gt; объект (Станция -&gt; Программа)</translation>
    </message>
    <message>
        <source>{0} forces active</source>
        <translation>Действует форсирований: {0}</translation>
    </message>
    <message>
        <source>NetPlc program {0}</source>
        <translation>NetPlc: {0}</translation>
    </message>
    <message>
        <source>no link to node {0} ({1})</source>
        <translation>нет связи с узлом {0} ({1})</translation>
    </message>
</context>
<context>
    <name>TagBrowser</name>
    <message>
        <source>Search tags: name, description, unit</source>
        <translation>Поиск тегов: имя, описание, единица</translation>
    </message>
    <message>
        <source>{0} ({1}{2}): no form element shows this type</source>
        <translation>{0} ({1}{2}): ни один элемент формы не показывает этот тип</translation>
    </message>
    <message>
        <source>{0} ({1}{2}): drag onto the form for a {3} bound to it</source>
        <translation>{0} ({1}{2}): перетащите на форму, чтобы создать привязанный к нему {3}</translation>
    </message>
    <message>
        <source>The station has no tags (tags.csv)</source>
        <translation>У станции нет тегов (tags.csv)</translation>
    </message>
</context>
<context>
    <name>TrendWidget</name>
    <message>
        <source>Pause (dragging or wheeling in the plot also pauses)</source>
        <translation>Пауза (перетаскивание или колесо мыши на графике тоже ставят паузу)</translation>
    </message>
    <message>
        <source>Back to live</source>
        <translation>Вернуться к текущему времени</translation>
    </message>
    <message>
        <source>%1 s</source>
        <translation>%1 с</translation>
    </message>
    <message>
        <source>%1 min</source>
        <translation>%1 мин</translation>
    </message>
    <message>
        <source>%1 h</source>
        <translation>%1 ч</translation>
    </message>
</context>
<context>
    <name>UsersDialog</name>
    <message>
        <source>Users</source>
        <translation>Пользователи</translation>
    </message>
    <message>
        <source>User</source>
        <translation>Пользователь</translation>
    </message>
    <message>
        <source>Role</source>
        <translation>Роль</translation>
    </message>
    <message>
        <source>Add…</source>
        <translation>Добавить…</translation>
    </message>
    <message>
        <source>Remove</source>
        <translation>Удалить</translation>
    </message>
    <message>
        <source>Password…</source>
        <translation>Пароль…</translation>
    </message>
    <message>
        <source>Add user</source>
        <translation>Новый пользователь</translation>
    </message>
    <message>
        <source>Name:</source>
        <translation>Имя:</translation>
    </message>
    <message>
        <source>Role:</source>
        <translation>Роль:</translation>
    </message>
    <message>
        <source>Password</source>
        <translation>Пароль</translation>
    </message>
    <message>
        <source>Password:</source>
        <translation>Пароль:</translation>
    </message>
    <message>
        <source>Add user {0}</source>
        <translation>Добавить пользователя {0}</translation>
    </message>
    <message>
        <source>Remove user {0}</source>
        <translation>Удалить пользователя {0}</translation>
    </message>
    <message>
        <source>Password of {0}</source>
        <translation>Пароль пользователя {0}</translation>
    </message>
</context>
<context>
    <name>ViewerWindow</name>
    <message>
        <source>the records of this archive carry no group</source>
        <translation>записи этого архива не содержат группы</translation>
    </message>
    <message>
        <source>any</source>
        <translation>любой</translation>
    </message>
    <message>
        <source>0 info and above</source>
        <translation>0 информация и выше</translation>
    </message>
    <message>
        <source>1 warning and above</source>
        <translation>1 предупреждение и выше</translation>
    </message>
    <message>
        <source>2 alarm and above</source>
        <translation>2 авария и выше</translation>
    </message>
    <message>
        <source>3 critical</source>
        <translation>3 критическая</translation>
    </message>
    <message>
        <source>NetPlc Station — journal viewer</source>
        <translation>NetPlc Station — просмотр журнала</translation>
    </message>
    <message>
        <source>&amp;Archive</source>
        <translation>&amp;Архив</translation>
    </message>
    <message>
        <source>&amp;Open…</source>
        <translation>&amp;Открыть…</translation>
    </message>
    <message>
        <source>&amp;Export selection to CSV…</source>
        <translation>&amp;Экспорт выборки в CSV…</translation>
    </message>
    <message>
        <source>&amp;Reload</source>
        <translation>&amp;Обновить</translation>
    </message>
    <message>
        <source>&amp;Close</source>
        <translation>&amp;Закрыть</translation>
    </message>
    <message>
        <source>no archive</source>
        <translation>нет архива</translation>
    </message>
    <message>
        <source>&lt;b&gt;Days&lt;/b&gt;</source>
        <translation>&lt;b&gt;Дни&lt;/b&gt;</translation>
    </message>
    <message>
        <source>&lt;b&gt;Filter&lt;/b&gt;</source>
        <translation>&lt;b&gt;Фильтр&lt;/b&gt;</translation>
    </message>
    <message>
        <source>Kind</source>
        <translation>Вид</translation>
    </message>
    <message>
        <source>Group</source>
        <translation>Группа</translation>
    </message>
    <message>
        <source>Type</source>
        <translation>Тип</translation>
    </message>
    <message>
        <source>Source</source>
        <translation>Источник</translation>
    </message>
    <message>
        <source>Text</source>
        <translation>Текст</translation>
    </message>
    <message>
        <source>From</source>
        <translation>С</translation>
    </message>
    <message>
        <source>To</source>
        <translation>По</translation>
    </message>
    <message>
        <source>Apply filter</source>
        <translation>Применить фильтр</translation>
    </message>
    <message>
        <source>Export CSV…</source>
        <translation>Экспорт CSV…</translation>
    </message>
    <message>
        <source>« First</source>
        <translation>« В начало</translation>
    </message>
    <message>
        <source>‹ Previous</source>
        <translation>‹ Назад</translation>
    </message>
    <message>
        <source>Next ›</source>
        <translation>Далее ›</translation>
    </message>
    <message>
        <source>Records</source>
        <translation>Записи</translation>
    </message>
    <message>
        <source>Series</source>
        <translation>Ряды</translation>
    </message>
    <message>
        <source>Journal viewer</source>
        <translation>Просмотр журнала</translation>
    </message>
    <message>
        <source>Export selection</source>
        <translation>Экспорт выборки</translation>
    </message>
    <message>
        <source>Open archive</source>
        <translation>Открыть архив</translation>
    </message>
    <message>
        <source>&lt;b&gt;Stations&lt;/b&gt;</source>
        <translation>&lt;b&gt;Станции&lt;/b&gt;</translation>
    </message>
    <message>
        <source>A message's type and worse; an alarm record by the priority of that severity (3 critical: priority 1, 2 alarm: 1-2, 1 warning: 1-3); a data record by its type</source>
        <translation>Тип сообщения и более тяжёлые; запись аварии — по приоритету этой тяжести (3 критическая: приоритет 1, 2 авария: 1-2, 1 предупреждение: 1-3); запись данных — по её типу</translation>
    </message>
    <message>
        <source>reading…</source>
        <translation>чтение…</translation>
    </message>
    <message>
        <source>archive unreadable: {0}</source>
        <translation>архив не читается: {0}</translation>
    </message>
</context>
<context>
    <name>HeaderLine</name>
    <message>
        <source>nobody logged in</source>
        <translation>никто не вошёл</translation>
    </message>
    <message>
        <source>Log out</source>
        <translation>Выйти</translation>
    </message>
    <message>
        <source>Log in…</source>
        <translation>Войти…</translation>
    </message>
</context>
<context>
    <name>quality</name>
    <message>
        <source>Stale: the data source of this element is not answering; the last value is shown</source>
        <translation>Устарело: источник данных этого элемента не отвечает; показано последнее значение</translation>
    </message>
    <message>
        <source>? initial: no value from the plant yet (the node has not answered since the start)</source>
        <translation>? нет данных: от объекта ещё нет значения (узел не отвечал с пуска)</translation>
    </message>
    <message>
        <source>? comm-fail: the node that fills this value is down; the last value is shown</source>
        <translation>? нет связи: узел, который даёт это значение, не отвечает; показано последнее значение</translation>
    </message>
    <message>
        <source>? not running: NetPlc is stopped; the last value is shown, nothing changes</source>
        <translation>? NetPlc остановлен: показано последнее значение, ничего не меняется</translation>
    </message>
    <message>
        <source>F forced: the value is forced by an engineer, not the plant's</source>
        <translation>F форсировано: значение задано инженером, а не получено с объекта</translation>
    </message>
    <message>
        <source>? station unreachable: the console's link to the station is lost; the last value is shown</source>
        <translation>? станция недоступна: связь пульта со станцией потеряна; показано последнее значение</translation>
    </message>
</context>
<context>
    <name>records</name>
    <message>
        <source>info</source>
        <translation>информация</translation>
    </message>
    <message>
        <source>warning</source>
        <translation>предупреждение</translation>
    </message>
    <message>
        <source>alarm</source>
        <translation>авария</translation>
    </message>
    <message>
        <source>critical</source>
        <translation>критическая</translation>
    </message>
    <message>
        <source>Time</source>
        <translation>Время</translation>
    </message>
    <message>
        <source>Kind</source>
        <translation>Вид</translation>
    </message>
    <message>
        <source>Group</source>
        <translation>Группа</translation>
    </message>
    <message>
        <source>Type</source>
        <translation>Тип</translation>
    </message>
    <message>
        <source>Source</source>
        <translation>Источник</translation>
    </message>
    <message>
        <source>No.</source>
        <translation>№</translation>
    </message>
    <message>
        <source>Value</source>
        <translation>Значение</translation>
    </message>
    <message>
        <source>Text</source>
        <translation>Текст</translation>
    </message>
    <message>
        <source>data</source>
        <translation>данные</translation>
    </message>
    <message>
        <source>message</source>
        <translation>сообщение</translation>
    </message>
    <message>
        <source>operator</source>
        <translation>оператор</translation>
    </message>
    <message>
        <source>system</source>
        <translation>система</translation>
    </message>
    <message>
        <source>message {0}</source>
        <translation>сообщение {0}</translation>
    </message>
</context>
<context>
    <name>words</name>
    <message>
        <source>viewer</source>
        <translation>наблюдатель</translation>
    </message>
    <message>
        <source>operator</source>
        <translation>оператор</translation>
    </message>
    <message>
        <source>engineer</source>
        <translation>инженер</translation>
    </message>
    <message>
        <source>admin</source>
        <translation>администратор</translation>
    </message>
    <message>
        <source>critical</source>
        <translation>критическая</translation>
    </message>
    <message>
        <source>high</source>
        <translation>высокая</translation>
    </message>
    <message>
        <source>medium</source>
        <translation>средняя</translation>
    </message>
    <message>
        <source>low</source>
        <translation>низкая</translation>
    </message>
    <message>
        <source>normal</source>
        <translation>норма</translation>
    </message>
    <message>
        <source>active-unacknowledged</source>
        <translation>активна, не квитирована</translation>
    </message>
    <message>
        <source>active-acknowledged</source>
        <translation>активна, квитирована</translation>
    </message>
    <message>
        <source>returned-unacknowledged</source>
        <translation>вернулась, не квитирована</translation>
    </message>
    <message>
        <source>shelved</source>
        <translation>отложена</translation>
    </message>
    <message>
        <source>suppressed</source>
        <translation>подавлена</translation>
    </message>
    <message>
        <source>out-of-service</source>
        <translation>выведена из работы</translation>
    </message>
    <message>
        <source>good</source>
        <translation>достоверно</translation>
    </message>
    <message>
        <source>initial</source>
        <translation>нет данных</translation>
    </message>
    <message>
        <source>stale</source>
        <translation>устарело</translation>
    </message>
    <message>
        <source>comm-fail</source>
        <translation>нет связи</translation>
    </message>
    <message>
        <source>not running</source>
        <translation>NetPlc остановлен</translation>
    </message>
    <message>
        <source>forced</source>
        <translation>форсировано</translation>
    </message>
    <message>
        <source>station unreachable</source>
        <translation>станция недоступна</translation>
    </message>
    <message>
        <source>{0}: nobody is logged in ({1} needed)</source>
        <translation>{0}: никто не вошёл (нужна роль «{1}»)</translation>
    </message>
    <message>
        <source>{0}: needs the {1} role; {2} is {3}</source>
        <translation>{0}: нужна роль «{1}»; {2} — {3}</translation>
    </message>
    <message>
        <source>{0}: {1} is no longer a user ({2} needed)</source>
        <translation>{0}: {1} больше не пользователь (нужна роль «{2}»)</translation>
    </message>
    <message>
        <source>The memory keeps the forced values until the program, a node or an operator writes them.</source>
        <translation>В памяти остаются форсированные значения, пока их не запишет программа, узел или оператор.</translation>
    </message>
    <message>
        <source>The memory keeps {0}, the forced value, until the program, a node or an operator writes it.</source>
        <translation>В памяти остаётся {0} — форсированное значение, пока его не запишет программа, узел или оператор.</translation>
    </message>
</context>
<context>
    <name>Faceplate</name>
    <message>
        <source>Faceplate: {0}</source>
        <translation>Карточка: {0}</translation>
    </message>
    <message>
        <source>No alarms on this tag</source>
        <translation>У этого тега нет аварий</translation>
    </message>
    <message>
        <source>Acknowledge</source>
        <translation>Квитировать</translation>
    </message>
    <message>
        <source>Shelve…</source>
        <translation>Отложить…</translation>
    </message>
    <message>
        <source>Set</source>
        <translation>Задать</translation>
    </message>
    <message>
        <source>empty: at its value</source>
        <translation>пусто: текущим значением</translation>
    </message>
    <message>
        <source>Force…</source>
        <translation>Форсировать…</translation>
    </message>
    <message>
        <source>Unforce…</source>
        <translation>Снять форсирование…</translation>
    </message>
    <message>
        <source>Set to ({0})</source>
        <translation>Задать ({0})</translation>
    </message>
    <message>
        <source>value</source>
        <translation>значение</translation>
    </message>
    <message>
        <source>Force</source>
        <translation>Форсирование</translation>
    </message>
    <message>
        <source>Close</source>
        <translation>Закрыть</translation>
    </message>
    <message>
        <source>F forced by {0}</source>
        <translation>F форсировал {0}</translation>
    </message>
    <message>
        <source>{0} is not a number</source>
        <translation>{0} — не число</translation>
    </message>
    <message>
        <source>Set {0}</source>
        <translation>Задать {0}</translation>
    </message>
    <message>
        <source>{0} is not forced: {1} is outside its range {2} .. {3}</source>
        <translation>{0} не форсирован: {1} вне диапазона {2} .. {3}</translation>
    </message>
    <message>
        <source>at its value (bumpless)</source>
        <translation>текущим значением (безударно)</translation>
    </message>
    <message>
        <source>to {0}</source>
        <translation>значением {0}</translation>
    </message>
    <message>
        <source>Force {0} {1}? The program and the nodes no longer change it until it is unforced.</source>
        <translation>Форсировать {0} {1}? Программа и узлы не будут его менять, пока форсирование не снято.</translation>
    </message>
    <message>
        <source>Force {0}</source>
        <translation>Форсировать {0}</translation>
    </message>
    <message>
        <source>Unforce</source>
        <translation>Снятие форсирования</translation>
    </message>
    <message>
        <source>Unforce {0}?</source>
        <translation>Снять форсирование {0}?</translation>
    </message>
    <message>
        <source>Unforce {0}</source>
        <translation>Снять форсирование {0}</translation>
    </message>
    <message>
        <source>No alarm of {0} to shelve</source>
        <translation>У {0} нет аварий, которые можно отложить</translation>
    </message>
</context>
<context>
    <name>ProgramMonitor</name>
    <message>
        <source>No program to list: give it with --program (the program, or the station folder for its symbols and tags too), or over Modbus name the station folder (main.py monitor STATION); watch addresses, symbols or tags in the table on the right.</source>
        <translation>Нет программы для листинга: укажите её через --program (программу или папку станции, чтобы были и её символы и теги), а по Modbus — папку станции (main.py monitor СТАНЦИЯ); адреса, символы и теги можно наблюдать в таблице справа.</translation>
    </message>
    <message>
        <source>Read-only over Modbus: Modbus has no users, so this monitor only watches. Write, force and step as a user of the station: over its OPC UA endpoint (main.py monitor opc.tcp://HOST:PORT/PATH) or at its own workstation. Its forces are unknown here.</source>
        <translation>Только просмотр по Modbus: у Modbus нет пользователей, поэтому монитор только наблюдает. Запись, форсирование и шаг — как пользователь станции: через её OPC UA (main.py monitor opc.tcp://ХОСТ:ПОРТ/ПУТЬ) или на её рабочем месте. Её форсирования здесь неизвестны.</translation>
    </message>
    <message>
        <source>Force {0} {1}? The program and the nodes no longer change it until it is unforced.</source>
        <translation>Форсировать {0} {1}? Программа и узлы не будут его менять, пока форсирование не снято.</translation>
    </message>
    <message>
        <source>F: unknown over Modbus</source>
        <translation>Ф: неизвестно по Modbus</translation>
    </message>
    <message>
        <source>F: {0} forced</source>
        <translation>Ф: форсировано {0}</translation>
    </message>
    <message>
        <source>Find (Enter: next)</source>
        <translation>Найти (Enter: далее)</translation>
    </message>
    <message>
        <source>Go to label…</source>
        <translation>К метке…</translation>
    </message>
    <message>
        <source>Step one scan</source>
        <translation>Один цикл</translation>
    </message>
    <message>
        <source>Unforce all</source>
        <translation>Снять все форсирования</translation>
    </message>
    <message>
        <source>Words:</source>
        <translation>Слова:</translation>
    </message>
    <message>
        <source>Address / symbol</source>
        <translation>Адрес / символ</translation>
    </message>
    <message>
        <source>Value</source>
        <translation>Значение</translation>
    </message>
    <message>
        <source>Forced</source>
        <translation>Форсировано</translation>
    </message>
    <message>
        <source>Uses: click a line to follow its operand</source>
        <translation>Использования: щёлкните строку, чтобы проследить её операнд</translation>
    </message>
    <message>
        <source>Watch: type an address (04000, 040042, 02000:w, 04001:b), a symbol or a tag</source>
        <translation>Наблюдение: введите адрес (04000, 040042, 02000:w, 04001:b), символ или тег</translation>
    </message>
    <message>
        <source>the station's forces are not in the Modbus map: see them at its own workstation</source>
        <translation>форсирований станции нет в карте Modbus: смотрите их на её рабочем месте</translation>
    </message>
    <message>
        <source>forces in effect: force &gt; program &gt; live</source>
        <translation>действуют форсирования: форсирование &gt; программа &gt; объект</translation>
    </message>
    <message>
        <source>nothing forced</source>
        <translation>ничего не форсировано</translation>
    </message>
    <message>
        <source>Refused: </source>
        <translation>Отказано: </translation>
    </message>
    <message>
        <source>Remove from watch</source>
        <translation>Убрать из наблюдения</translation>
    </message>
    <message>
        <source>its value</source>
        <translation>его значение</translation>
    </message>
    <message>
        <source>at its value {0} (bumpless)</source>
        <translation>текущим значением {0} (безударно)</translation>
    </message>
    <message>
        <source>to {0}</source>
        <translation>значением {0}</translation>
    </message>
    <message>
        <source>Force</source>
        <translation>Форсирование</translation>
    </message>
    <message>
        <source>Unforce</source>
        <translation>Снятие форсирования</translation>
    </message>
    <message>
        <source>Unforce {0}?</source>
        <translation>Снять форсирование {0}?</translation>
    </message>
    <message>
        <source>Unforce all {0} forces?</source>
        <translation>Снять все форсирования ({0})?</translation>
    </message>
    <message>
        <source>Force {0} at its value (bumpless)</source>
        <translation>Форсировать {0} текущим значением (безударно)</translation>
    </message>
    <message>
        <source>Force {0} to…</source>
        <translation>Форсировать {0} значением…</translation>
    </message>
    <message>
        <source>Unforce {0}</source>
        <translation>Снять форсирование {0}</translation>
    </message>
    <message>
        <source>Force {0} to ({1}, {2} .. {3}):</source>
        <translation>Форсировать {0} значением ({1}, {2} .. {3}):</translation>
    </message>
    <message>
        <source>value</source>
        <translation>значение</translation>
    </message>
    <message>
        <source>Force {0} to (decimal, 0x1F or 1Fh):</source>
        <translation>Форсировать {0} значением (десятичное, 0x1F или 1Fh):</translation>
    </message>
    <message>
        <source>Uses of {0} ({1}): {2} lines</source>
        <translation>Использования {0} ({1}): строк {2}</translation>
    </message>
    <message>
        <source>Follow uses of {0} {1}</source>
        <translation>Использования {0} {1}</translation>
    </message>
    <message>
        <source>Watch {0}</source>
        <translation>Наблюдать {0}</translation>
    </message>
</context>
<context>
    <name>ProgramWindow</name>
    <message>
        <source>Program — {0}</source>
        <translation>Программа — {0}</translation>
    </message>
    <message>
        <source> (read-only)</source>
        <translation> (только просмотр)</translation>
    </message>
</context>
<context>
    <name>TrendWindow</name>
    <message>
        <source>Run-time trend</source>
        <translation>Тренд</translation>
    </message>
    <message>
        <source>Search tags: name, description, unit</source>
        <translation>Поиск тегов: имя, описание, единица</translation>
    </message>
    <message>
        <source>Add to the trend</source>
        <translation>Добавить в тренд</translation>
    </message>
    <message>
        <source>Live</source>
        <translation>Реальное время</translation>
    </message>
    <message>
        <source>Follow the live values; panning or zooming the plot stops following</source>
        <translation>Следовать за текущими значениями; сдвиг или масштабирование графика прекращает слежение</translation>
    </message>
    <message>
        <source>The trends saved by the user on duty</source>
        <translation>Тренды, сохранённые текущим пользователем</translation>
    </message>
    <message>
        <source>Open</source>
        <translation>Открыть</translation>
    </message>
    <message>
        <source>Save as…</source>
        <translation>Сохранить как…</translation>
    </message>
    <message>
        <source>Remove pen</source>
        <translation>Убрать перо</translation>
    </message>
    <message>
        <source>Export PNG…</source>
        <translation>Экспорт PNG…</translation>
    </message>
    <message>
        <source>PNG image (*.png)</source>
        <translation>Изображение PNG (*.png)</translation>
    </message>
    <message>
        <source>Export CSV…</source>
        <translation>Экспорт CSV…</translation>
    </message>
    <message>
        <source>CSV (*.csv)</source>
        <translation>CSV (*.csv)</translation>
    </message>
    <message>
        <source>Span</source>
        <translation>Интервал</translation>
    </message>
    <message>
        <source>Pen</source>
        <translation>Перо</translation>
    </message>
    <message>
        <source>Min</source>
        <translation>Мин</translation>
    </message>
    <message>
        <source>Max</source>
        <translation>Макс</translation>
    </message>
    <message>
        <source>Mean</source>
        <translation>Среднее</translation>
    </message>
    <message>
        <source>{0} min</source>
        <translation>{0} мин</translation>
    </message>
    <message>
        <source>{0} h</source>
        <translation>{0} ч</translation>
    </message>
    <message>
        <source>Double-click to add {0} to the trend</source>
        <translation>Двойной щелчок добавляет {0} в тренд</translation>
    </message>
    <message>
        <source>{0}: no such tag in this station</source>
        <translation>{0}: такого тега в станции нет</translation>
    </message>
    <message>
        <source>The archive of {0} could not be read: {1}</source>
        <translation>Архив за {0} не прочитан: {1}</translation>
    </message>
    <message>
        <source>A {0}   B {1}   B − A {2} s</source>
        <translation>A {0}   B {1}   B − A {2} с</translation>
    </message>
    <message>
        <source>The trend was not saved: {0}</source>
        <translation>Тренд не сохранён: {0}</translation>
    </message>
    <message>
        <source>Run-time trend: {0}</source>
        <translation>Тренд: {0}</translation>
    </message>
    <message>
        <source>Save trend</source>
        <translation>Сохранить тренд</translation>
    </message>
    <message>
        <source>Name of the trend</source>
        <translation>Имя тренда</translation>
    </message>
    <message>
        <source>No trend {0} of this user</source>
        <translation>У этого пользователя нет тренда {0}</translation>
    </message>
    <message>
        <source>Export</source>
        <translation>Экспорт</translation>
    </message>
    <message>
        <source>{0} could not be written</source>
        <translation>{0} не записан</translation>
    </message>
    <message>
        <source>{0} could not be written: {1}</source>
        <translation>{0} не записан: {1}</translation>
    </message>
</context>
<context>
    <name>AnalogOutput</name>
    <message>
        <source>Input is disabled for this element</source>
        <translation>Ввод для этого элемента отключён</translation>
    </message>
    <message>
        <source>"{0}" is not a number</source>
        <translation>«{0}» — не число</translation>
    </message>
    <message>
        <source>{0} is out of range {1} … {2}{3}</source>
        <translation>{0} вне диапазона {1} … {2}{3}</translation>
    </message>
    <message>
        <source>Set to {0}{1}</source>
        <translation>Задано {0}{1}</translation>
    </message>
    <message>
        <source>Set</source>
        <translation>Задать</translation>
    </message>
    <message>
        <source>{0}: writes word {1}; range {2} … {3}{4}</source>
        <translation>{0}: пишет слово {1}; диапазон {2} … {3}{4}</translation>
    </message>
</context>
<context>
    <name>AnalogWidget</name>
    <message>
        <source>{0}: word {1}, {2} … {3}{4}</source>
        <translation>{0}: слово {1}, {2} … {3}{4}</translation>
    </message>
    <message>
        <source>; double-click resets the maximum</source>
        <translation>; двойной щелчок сбрасывает максимум</translation>
    </message>
    <message>
        <source>max {0}</source>
        <translation>макс. {0}</translation>
    </message>
</context>
<context>
    <name>JournalWidget</name>
    <message>
        <source>all types</source>
        <translation>все типы</translation>
    </message>
    <message>
        <source>warnings and worse</source>
        <translation>предупреждения и выше</translation>
    </message>
    <message>
        <source>alarms and worse</source>
        <translation>аварии и выше</translation>
    </message>
    <message>
        <source>critical</source>
        <translation>критические</translation>
    </message>
    <message>
        <source>Today</source>
        <translation>Сегодня</translation>
    </message>
    <message>
        <source>all kinds</source>
        <translation>все виды</translation>
    </message>
    <message>
        <source>as configured</source>
        <translation>как настроено</translation>
    </message>
    <message>
        <source>all groups</source>
        <translation>все группы</translation>
    </message>
    <message>
        <source>group </source>
        <translation>группа </translation>
    </message>
    <message>
        <source>no archive configured</source>
        <translation>архив не задан</translation>
    </message>
    <message>
        <source>no archive yet</source>
        <translation>архива ещё нет</translation>
    </message>
    <message>
        <source>archive unreadable: {0}</source>
        <translation>архив не читается: {0}</translation>
    </message>
    <message>
        <source>{0} of {1} records</source>
        <translation>записей: {0} из {1}</translation>
    </message>
    <message>
        <source>{0} records</source>
        <translation>записей: {0}</translation>
    </message>
</context>
<context>
    <name>SyncWidget</name>
    <message>
        <source>{0}: period {1}, phase {2}</source>
        <translation>{0}: период {1}, фаза {2}</translation>
    </message>
    <message>
        <source>disabled</source>
        <translation>отключён</translation>
    </message>
</context>
<context>
    <name>ZoomArea</name>
    <message>
        <source>fit width</source>
        <translation>по ширине</translation>
    </message>
    <message>
        <source>fit window</source>
        <translation>по окну</translation>
    </message>
</context>
</TS>
